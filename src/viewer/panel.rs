//! The on-screen panel (egui): the view's main settings as widgets, beside the keys that
//! change the same values. The main thread runs it (window events in, [`ViewState`]
//! edited in place) and hands the tessellated result to the render thread in a
//! [`PanelFrame`]; the render thread draws it over the tone-mapped frame
//! ([`crate::vk::Overlay`]) and, while nothing else is drawn, presents the last frame again
//! when the panel changes. Tab shows or hides it; `--no-panel` starts it hidden.

use egui::epaint::ImageDelta;
use egui::{ClippedPrimitive, TextureId};

use super::*;
use crate::light::clamp_light;
use crate::transfer::PRESETS;

/// What the panel leaves for the render thread.
#[derive(Default)]
pub(super) struct PanelFrame {
    /// Increases with every change of what the panel shows.
    pub(super) generation: u64,
    pub(super) visible: bool,
    pub(super) primitives: Arc<Vec<ClippedPrimitive>>,
    pub(super) pixels_per_point: f32,
    /// Texture updates and frees not yet applied, in order.
    pub(super) textures_set: Vec<(TextureId, ImageDelta)>,
    pub(super) textures_free: Vec<TextureId>,
    /// The last frame's quality and time, written by the render thread.
    pub(super) status: String,
}

/// What a panel interaction asks of the main thread beyond the view state.
pub(super) enum PanelAction {
    /// Load this transfer-function preset.
    TransferFunctions(String),
    /// Put this environment behind the volume.
    Environment(EnvChoice),
}

/// The environment the panel's combo box chose: the scene's own (its map, the sky or
/// none, as its file or command line said), the built-in sky, or none (the flat
/// background colour, which the panel then offers).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum EnvChoice {
    Scene,
    Sky,
    None,
}

pub(super) struct Panel {
    egui: egui::Context,
    winit: egui_winit::State,
    pub(super) shared: Arc<Mutex<PanelFrame>>,
    visible: bool,
    /// An event or an animation asks for the panel to be run again.
    dirty: bool,
    /// What the panel last showed (it runs again when either changed).
    last: Option<(ViewState, String)>,
    /// The transfer functions' preset shown in the combo box.
    preset: String,
    /// The volume's half diagonal: the clipping plane's offset range.
    radius: f32,
    /// The environment chosen, and what the scene's own is (its name; whether it is none).
    env: EnvChoice,
    scene_env: (String, bool),
}

impl Panel {
    /// `scene_env`: the scene's own environment, its name and whether it is none.
    pub(super) fn new(
        window: &Window,
        visible: bool,
        radius: f32,
        scene_env: (String, bool),
    ) -> Self {
        let egui = egui::Context::default();
        // No shadow: the panel darkens no pixel of the frame outside its own box.
        egui.style_mut(|s| s.visuals.window_shadow = egui::Shadow::NONE);
        let winit = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        Self {
            egui,
            winit,
            shared: Arc::new(Mutex::new(PanelFrame {
                visible,
                ..PanelFrame::default()
            })),
            visible,
            dirty: true,
            last: None,
            preset: "(the scene's)".into(),
            radius,
            env: EnvChoice::Scene,
            scene_env,
        }
    }

    /// A reloaded scene brings its own environment back (the render thread puts it up).
    pub(super) fn set_scene_env(&mut self, scene_env: (String, bool)) {
        self.scene_env = scene_env;
        self.env = EnvChoice::Scene;
        self.dirty = true;
    }

    /// Feed a window event; true when the panel took it (the pointer is over it or a
    /// widget is being dragged), so the view's own controls leave it alone.
    pub(super) fn on_event(&mut self, window: &Window, event: &WindowEvent) -> bool {
        if !self.visible {
            return false;
        }
        let r = self.winit.on_window_event(window, event);
        self.dirty |= r.repaint;
        r.consumed
    }

    pub(super) fn toggle(&mut self) -> bool {
        self.visible = !self.visible;
        self.dirty = true;
        self.visible
    }

    pub(super) fn set_radius(&mut self, radius: f32) {
        self.radius = radius;
    }

    /// Run the panel if anything it shows may have changed: widgets edit `state`; other
    /// requests go to `actions`. Returns whether it wants to run again soon (an
    /// animation).
    pub(super) fn update(
        &mut self,
        window: &Window,
        state: &Mutex<ViewState>,
        actions: &mut Vec<PanelAction>,
    ) -> bool {
        let view = state.lock().unwrap().clone();
        let status = self.shared.lock().unwrap().status.clone();
        let now = (view, status);
        if !self.dirty && self.last.as_ref() == Some(&now) {
            return false;
        }
        self.dirty = false;
        let (mut edited, status) = now;
        let before = edited.clone();
        let input = self.winit.take_egui_input(window);
        let visible = self.visible;
        let mut env = EnvControl {
            choice: &mut self.env,
            scene: &self.scene_env,
        };
        let (radius, preset) = (self.radius, &mut self.preset);
        let output = self.egui.run(input, |ctx| {
            if visible {
                controls(ctx, &mut edited, &status, radius, preset, &mut env, actions);
            }
        });
        if edited != before {
            for said in switched(&before, &edited) {
                println!("{said}");
            }
            *state.lock().unwrap() = edited.clone();
        }
        self.winit
            .handle_platform_output(window, output.platform_output);
        let primitives = self.egui.tessellate(output.shapes, output.pixels_per_point);
        let again = output
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .is_some_and(|v| v.repaint_delay < Duration::from_millis(250));
        {
            let mut s = self.shared.lock().unwrap();
            s.generation += 1;
            s.visible = visible;
            s.primitives = Arc::new(primitives);
            s.pixels_per_point = output.pixels_per_point;
            s.textures_set.extend(output.textures_delta.set);
            s.textures_free.extend(output.textures_delta.free);
        }
        self.last = Some((edited, status));
        self.dirty = again;
        again
    }
}

/// What the panel switched (not the sliders' every step), said as the keys say it.
fn switched(before: &ViewState, after: &ViewState) -> Vec<String> {
    let mut said = Vec::new();
    if before.model != after.model {
        said.push(format!("model {}", after.model.name()));
    }
    match (before.opts.sweep.clip, after.opts.sweep.clip) {
        (None, Some((n, o))) => said.push(format!(
            "clipping on: n = ({:.2}, {:.2}, {:.2}), offset {o:.2}",
            n.x, n.y, n.z
        )),
        (Some(_), None) => said.push("clipping off".into()),
        _ => {}
    }
    said
}

/// Light direction (towards the light) as azimuth and elevation in degrees, the camera's
/// convention: azimuth about +y from +z towards +x.
fn light_angles(towards: Vec3) -> (f32, f32) {
    let t = towards.normalize();
    (
        t.x.atan2(t.z).to_degrees(),
        t.y.clamp(-1.0, 1.0).asin().to_degrees(),
    )
}

fn from_angles(azimuth: f32, elevation: f32) -> Vec3 {
    let (a, e) = (azimuth.to_radians(), elevation.to_radians());
    Vec3::new(e.cos() * a.sin(), e.sin(), e.cos() * a.cos())
}

/// The ambient slider's top, in `--ambient-level`'s units (linear irradiance; the default
/// light's is 1).
const MAX_AMBIENT_LEVEL: f32 = 2.0;

/// The panel's environment combo box: what it shows and the scene's own environment.
struct EnvControl<'a> {
    choice: &'a mut EnvChoice,
    scene: &'a (String, bool),
}

impl EnvControl<'_> {
    fn label(&self, choice: EnvChoice) -> String {
        match choice {
            EnvChoice::Scene => format!("the scene's ({})", self.scene.0),
            EnvChoice::Sky => "sky".into(),
            EnvChoice::None => "none (background colour)".into(),
        }
    }

    /// Whether the flat background colour is what lies behind the volume.
    fn is_none(&self) -> bool {
        match *self.choice {
            EnvChoice::Scene => self.scene.1,
            EnvChoice::Sky => false,
            EnvChoice::None => true,
        }
    }

    /// The combo box, the background colour where no map is behind the volume, the
    /// map's rotation where one is.
    fn show(&mut self, ui: &mut egui::Ui, v: &mut ViewState, actions: &mut Vec<PanelAction>) {
        egui::ComboBox::from_label("environment")
            .selected_text(self.label(*self.choice))
            .show_ui(ui, |ui| {
                for c in [EnvChoice::Scene, EnvChoice::Sky, EnvChoice::None] {
                    if ui
                        .selectable_label(*self.choice == c, self.label(c))
                        .clicked()
                        && *self.choice != c
                    {
                        *self.choice = c;
                        actions.push(PanelAction::Environment(c));
                    }
                }
            });
        if self.is_none() {
            // Linear RGB, as --background takes it.
            let b = &mut v.opts.background;
            let mut colour = egui::Rgba::from_rgb(b[0], b[1], b[2]);
            ui.horizontal(|ui| {
                let picked = egui::widgets::color_picker::color_edit_button_rgba(
                    ui,
                    &mut colour,
                    egui::widgets::color_picker::Alpha::Opaque,
                );
                ui.label("background");
                if picked.changed() {
                    b[0] = colour.r();
                    b[1] = colour.g();
                    b[2] = colour.b();
                }
            });
        } else {
            ui.add(
                egui::Slider::new(&mut v.opts.sweep.env_rotation, -180.0..=180.0)
                    .text("environment rotation °"),
            );
        }
    }
}

fn controls(
    ctx: &egui::Context,
    v: &mut ViewState,
    status: &str,
    radius: f32,
    preset: &mut String,
    env: &mut EnvControl,
    actions: &mut Vec<PanelAction>,
) {
    // Folded at first (a title bar in the corner; a click opens it), so that a first look
    // sees the volume, not the widgets.
    egui::Window::new("refrakt settings")
        .default_pos([8.0, 8.0])
        .default_open(false)
        .resizable(false)
        .show(ctx, |ui| {
            ui.spacing_mut().slider_width = 110.0;
            // One line whatever its length, so the widgets below stay in place.
            let status = if status.is_empty() {
                "rendering the first frame"
            } else {
                status
            };
            ui.add(egui::Label::new(status).truncate());
            ui.label("Tab hides this panel, H prints the keys");
            ui.separator();
            egui::ComboBox::from_label("model")
                .selected_text(v.model.name())
                .show_ui(ui, |ui| {
                    for m in Model::ALL {
                        ui.selectable_value(&mut v.model, m, m.name());
                    }
                });
            egui::ComboBox::from_label("transfer functions")
                .selected_text(preset.as_str())
                .show_ui(ui, |ui| {
                    for (name, _) in PRESETS {
                        if ui.selectable_label(preset == name, *name).clicked() {
                            *preset = name.to_string();
                            actions.push(PanelAction::TransferFunctions(name.to_string()));
                        }
                    }
                });
            ui.add(
                egui::Slider::new(
                    &mut v.opts.sample_distance,
                    LIMITS_SAMPLE_DISTANCE.0..=LIMITS_SAMPLE_DISTANCE.1,
                )
                .logarithmic(true)
                .text("sample distance"),
            );
            ui.separator();
            let light = v.opts.light_mut();
            let (mut az, mut el) = light_angles(light.towards());
            let turned = ui
                .add(egui::Slider::new(&mut az, -180.0..=180.0).text("light azimuth °"))
                .changed()
                | ui.add(egui::Slider::new(&mut el, -89.0..=89.0).text("light elevation °"))
                    .changed();
            if turned {
                // Kept within reach of the sweep as the keys and drags keep it.
                let towards = clamp_light(from_angles(az, el), &v.camera);
                super::move_light(light, |_| towards);
            }
            let mut intensity = light.colour.into_iter().fold(0.0f32, f32::max);
            let hue = light
                .colour
                .map(|c| if intensity > 0.0 { c / intensity } else { 1.0 });
            if ui
                .add(egui::Slider::new(&mut intensity, 0.0..=8.0).text("light intensity"))
                .changed()
            {
                light.colour = hue.map(|c| c * intensity);
            }
            ui.add(
                egui::Slider::new(&mut light.softness, LIMITS_SOFTNESS.0..=LIMITS_SOFTNESS.1)
                    .text("softness"),
            );
            let s = &mut v.opts.sweep;
            ui.add(egui::Slider::new(&mut s.eta_scale, 0.0..=MAX_ETA_SCALE).text("η scale"));
            ui.add(
                egui::Slider::new(&mut s.roughness, LIMITS_ROUGHNESS.0..=LIMITS_ROUGHNESS.1)
                    .text("roughness"),
            );
            ui.separator();
            let mut clip = s.clip.is_some();
            if ui.checkbox(&mut clip, "clipping plane").changed() {
                s.clip = clip.then(|| {
                    let (eye, ..) = v.camera.frame();
                    (eye.normalize(), 0.0)
                });
            }
            if let Some((n, offset)) = &mut s.clip {
                ui.add(egui::Slider::new(offset, -radius..=radius).text("clip offset"));
                if ui.button("clip facing the camera").clicked() {
                    let (eye, ..) = v.camera.frame();
                    *n = eye.normalize();
                }
            }
            ui.separator();
            // The environment and the ambient level are the refractive and eikonal
            // models' (the others draw the background colour and take no ambient light).
            if matches!(v.model, Model::Refract | Model::Eikonal) {
                env.show(ui, v, actions);
                let s = &mut v.opts.sweep;
                let mut level = s.ambient.into_iter().fold(0.0f32, f32::max);
                let hue = s.ambient.map(|c| if level > 0.0 { c / level } else { 1.0 });
                if ui
                    .add(
                        egui::Slider::new(&mut level, 0.0..=MAX_AMBIENT_LEVEL)
                            .text("ambient level"),
                    )
                    .changed()
                {
                    s.ambient = hue.map(|c| c * level);
                }
            }
            ui.add(egui::Slider::new(&mut v.tone.exposure, -8.0..=8.0).text("exposure (stops)"));
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_angles_invert() {
        for (az, el) in [(0.0, 0.0), (90.0, 30.0), (-135.0, -45.0), (170.0, 80.0)] {
            let (a, e) = light_angles(from_angles(az, el));
            assert!(
                (a - az).abs() < 1e-3 && (e - el).abs() < 1e-3,
                "{az},{el} -> {a},{e}"
            );
        }
        // +x is azimuth 90 (the camera's convention: azimuth from +z towards +x).
        let (a, e) = light_angles(Vec3::X);
        assert!((a - 90.0).abs() < 1e-4 && e.abs() < 1e-4);
    }
}
