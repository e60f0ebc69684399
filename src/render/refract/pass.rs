//! The sweep's GPU resources: state images, render passes, framebuffers, descriptor sets
//! and pipelines, made once per viewport size and ray budget.

use std::collections::HashMap;

use super::*;

/// An image of two layers (the ping-pong of the plane sweep) with a view of each layer:
/// the six state buffers; the forward transport's irradiance (rgb) and light direction
/// (luminance-weighted sum of unit directions, weight in w) of the last two planes, plane
/// i in layer i % 2; and its light rays.
pub(crate) struct StateImage {
    pub(crate) image: Image,
    pub(crate) layers: [LayerView; 2],
}

impl StateImage {
    pub(crate) fn new(ctx: &Context, size: [u32; 2], name: &str) -> Result<Self> {
        let image = Image::new(
            ctx,
            ImageDesc {
                kind: ImageKind::D2Array,
                format: STATE_FORMAT,
                extent: [size[0], size[1], 1],
                layers: 2,
                usage: vk::usage::COLOR_ATTACHMENT
                    | vk::usage::SAMPLED
                    | vk::usage::STORAGE
                    | vk::usage::TRANSFER_SRC,
            },
            name,
        )?;
        let layers = [image.layer_view(0)?, image.layer_view(1)?];
        Ok(Self { image, layers })
    }
}

pub(crate) struct SweepPass {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) params: Buffer,
    pub(crate) states: Vec<StateImage>,
    pub(crate) render_pass: RenderPass,
    pub(crate) framebuffers: [Framebuffer; 2],
    pub(crate) sweep_set: DescriptorSet,
    pub(crate) setup_set: DescriptorSet,
    pub(crate) composite_set: DescriptorSet,
    pub(crate) setup: ComputePipeline,
    /// The plane pipelines per feature set (specialization constants); the set with
    /// every feature on is made with the pass, the others on the first frame that
    /// needs them.
    pub(crate) planes: HashMap<Features, PlanePipelines>,
    pub(crate) have_gradient: bool,
    pub(crate) floor: GraphicsPipeline,
    pub(crate) forward: Option<ForwardPipelines>,
    pub(crate) irradiance: [StateImage; 2],
    /// The forward transport's light rays (flux + view x; v + view y): `rays_per_pixel`
    /// texels per screen pixel (the screen's width, that many times its height).
    pub(crate) rays: [StateImage; 2],
    pub(crate) rays_per_pixel: u32,
    pub(crate) splat_pass: RenderPass,
    pub(crate) splat_framebuffers: [Framebuffer; 2],
    /// Forward transport: the light rays' pass (the two light buffers) and the viewing
    /// rays' pass (the other four), per written layer.
    pub(crate) light_pass: RenderPass,
    pub(crate) light_framebuffers: [Framebuffer; 2],
    pub(crate) view_pass: RenderPass,
    pub(crate) view_framebuffers: [Framebuffer; 2],
    pub(crate) counters: Buffer,
    pub(crate) composite: ComputePipeline,
    pub(crate) output: FrameTarget,
    pub(crate) env_params: Buffer,
}

/// The features a frame uses that the plane shaders can leave out: specialization
/// constants 1-4 (glsl/sweep_common.glsl), each on exactly when its runtime condition
/// can hold, so switching one off changes no image (tested) and costs nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct Features {
    pub(crate) specular: bool,
    pub(crate) clip: bool,
    pub(crate) reflections: bool,
    pub(crate) soft_light: bool,
}

impl Features {
    pub(crate) const ALL: Features = Features {
        specular: true,
        clip: true,
        reflections: true,
        soft_light: true,
    };

    pub(crate) fn of(sweep: &SweepOptions) -> Self {
        if !sweep.levers.specialize {
            return Self::ALL;
        }
        Self {
            specular: sweep.specular > 0.0,
            clip: sweep.clip.is_some(),
            reflections: sweep.reflections,
            soft_light: sweep.light.softness > 0.0,
        }
    }

    /// Constant 0 (the gradient volume is bound), then 1-4.
    fn constants(self, have_gradient: bool) -> [u32; 5] {
        [
            have_gradient as u32,
            self.specular as u32,
            self.clip as u32,
            self.reflections as u32,
            self.soft_light as u32,
        ]
    }
}

/// The plane pipelines that read the specialization constants: the backward sweep's
/// and the forward transport's light-ray and viewing-ray passes.
pub(crate) struct PlanePipelines {
    pub(crate) sweep: GraphicsPipeline,
    pub(crate) forward: Option<ForwardPlanes>,
}

impl PlanePipelines {
    /// `passes`: the backward sweep's, the light rays', the viewing rays'.
    fn new(
        ctx: &Context,
        passes: [&RenderPass; 3],
        set: &DescriptorSet,
        constants: [u32; 5],
        forward: bool,
    ) -> Result<Self> {
        let plane = |fragment, pass, name: &str| {
            let desc = GraphicsDesc {
                constants: &constants,
                ..GraphicsDesc::fullscreen(
                    shaders::FULLSCREEN_VERT,
                    fragment,
                    pass,
                    set,
                    std::mem::size_of::<PlanePush>() as u32,
                )
            };
            GraphicsPipeline::new(ctx, &desc, name)
        };
        let [sweep_pass, light_pass, view_pass] = passes;
        Ok(Self {
            sweep: plane(shaders::SWEEP_FRAG, sweep_pass, "sweep plane")?,
            forward: if forward {
                Some(ForwardPlanes {
                    light: plane(
                        shaders::SWEEP_LIGHT_FORWARD_FRAG,
                        light_pass,
                        "sweep light rays",
                    )?,
                    light_soft: plane(
                        shaders::SWEEP_LIGHT_FORWARD_SOFT_FRAG,
                        light_pass,
                        "sweep light rays (soft)",
                    )?,
                    view: plane(
                        shaders::SWEEP_VIEW_FORWARD_FRAG,
                        view_pass,
                        "sweep viewing rays",
                    )?,
                })
            } else {
                None
            },
        })
    }
}

pub(crate) struct ForwardPlanes {
    pub(crate) light: GraphicsPipeline,
    pub(crate) light_soft: GraphicsPipeline,
    pub(crate) view: GraphicsPipeline,
}

/// The forward transport's pipelines that do not depend on the features, on the plane
/// set's layout so that switching between them leaves the descriptor set bound.
pub(crate) struct ForwardPipelines {
    pub(crate) splat: GraphicsPipeline,
    /// Largest splat half-width the device's point sizes allow.
    pub(crate) max_half_width: f32,
}

impl SweepPass {
    pub fn new(inputs: &Inputs, width: u32, height: u32, rays_per_pixel: u32) -> Result<Self> {
        let Inputs {
            ctx,
            volume,
            gradient,
            tf,
            preint,
            linear: sampler,
            env,
            ..
        } = inputs;
        let (ctx, volume, tf, preint, sampler) = (*ctx, *volume, *tf, *preint, *sampler);
        let max_image = ctx.info().limits.max_image_dimension2_d;
        ensure!(
            (height as u64) * (rays_per_pixel as u64) <= max_image as u64,
            "{rays_per_pixel} light rays per pixel need ray images {width}x{} texels; device \
             '{}' allows {max_image} per side",
            height as u64 * rays_per_pixel as u64,
            ctx.info().name
        );
        let max_attachments = ctx.info().limits.max_color_attachments;
        if max_attachments < 6 {
            bail!(
                "the plane sweep writes 6 colour attachments per plane; device '{}' allows {}",
                ctx.info().name,
                max_attachments
            );
        }
        let params = Buffer::uniform::<SweepParams>(ctx, "sweep params")?;
        let states = StateBuffer::ALL
            .into_iter()
            .map(|b| StateImage::new(ctx, [width, height], b.name()))
            .collect::<Result<Vec<_>>>()?;
        let render_pass = RenderPass::new(
            ctx,
            &[STATE_FORMAT; 6],
            Access::AttachmentGeneral,
            "sweep plane",
        )?;
        let fb = |layer: usize| {
            let views: Vec<&LayerView> = states.iter().map(|s| &s.layers[layer]).collect();
            Framebuffer::new(
                ctx,
                &render_pass,
                &views,
                width,
                height,
                &format!("sweep write layer {layer}"),
            )
        };
        let framebuffers = [fb(0)?, fb(1)?];

        let irradiance = [
            StateImage::new(ctx, [width, height], "irradiance")?,
            StateImage::new(ctx, [width, height], "irradiance direction")?,
        ];
        let ray_size = [width, height * rays_per_pixel];
        let rays = [
            StateImage::new(ctx, ray_size, "light rays")?,
            StateImage::new(ctx, ray_size, "light ray directions")?,
        ];
        let splat_pass = RenderPass::cleared(
            ctx,
            &[STATE_FORMAT; 2],
            Access::AttachmentGeneral,
            "light splat",
        )?;
        let splat_fb = |layer: usize| {
            Framebuffer::new(
                ctx,
                &splat_pass,
                &[&irradiance[0].layers[layer], &irradiance[1].layers[layer]],
                width,
                height,
                &format!("light splat layer {layer}"),
            )
        };
        let splat_framebuffers = [splat_fb(0)?, splat_fb(1)?];
        let light_pass = RenderPass::new(
            ctx,
            &[STATE_FORMAT; 2],
            Access::AttachmentGeneral,
            "sweep light rays",
        )?;
        let view_pass = RenderPass::new(
            ctx,
            &[STATE_FORMAT; 4],
            Access::AttachmentGeneral,
            "sweep viewing rays",
        )?;
        let sub_fb =
            |pass: &RenderPass, range: std::ops::Range<usize>, layer: usize, name: &str| {
                let views: Vec<&LayerView> =
                    states[range].iter().map(|s| &s.layers[layer]).collect();
                Framebuffer::new(
                    ctx,
                    pass,
                    &views,
                    width,
                    height,
                    &format!("{name} layer {layer}"),
                )
            };
        let ray_fb = |layer: usize| {
            Framebuffer::new(
                ctx,
                &light_pass,
                &[&rays[0].layers[layer], &rays[1].layers[layer]],
                width,
                height * rays_per_pixel,
                &format!("sweep light rays layer {layer}"),
            )
        };
        let light_framebuffers = [ray_fb(0)?, ray_fb(1)?];
        let view_framebuffers = [
            sub_fb(&view_pass, 2..6, 0, "sweep viewing rays")?,
            sub_fb(&view_pass, 2..6, 1, "sweep viewing rays")?,
        ];
        let counters = Buffer::new(
            ctx,
            16,
            vk::usage::STORAGE_BUFFER
                | vk::usage::BUFFER_TRANSFER_DST
                | vk::usage::BUFFER_TRANSFER_SRC,
            vk::Memory::Gpu,
            "sweep clamp counters",
        )?;

        let common = [
            Binding::Uniform(&params),
            Binding::Texture(volume, sampler),
            Binding::Texture(tf, sampler),
            Binding::Texture(preint, sampler),
        ];
        let mut sampled: Vec<Binding> = common.to_vec();
        for s in &states {
            for view in &s.layers {
                sampled.push(Binding::LayerTexture(view, sampler, Access::SampledGeneral));
            }
        }
        let mut plane_bindings = sampled.clone();
        for irr in &irradiance {
            for view in &irr.layers {
                plane_bindings.push(Binding::LayerTexture(view, sampler, Access::SampledGeneral));
            }
        }
        plane_bindings.push(Binding::Storage(&counters));
        for r in &rays {
            for view in &r.layers {
                plane_bindings.push(Binding::LayerTexture(view, sampler, Access::SampledGeneral));
            }
        }
        // Binding 25: the environment for Fresnel reflections (glsl/sweep_light.glsl).
        plane_bindings.push(Binding::Texture(env.map, sampler));
        // Binding 26: the smoothed gradient volume (render::gradient, glsl/sweep_light.glsl);
        // without one the shaders compute normals on the fly (specialization constant 0)
        // and never read the binding, which the volume then fills.
        plane_bindings.push(Binding::Texture(gradient.unwrap_or(volume), sampler));
        let have_gradient = gradient.is_some();
        let sweep_set = DescriptorSet::new(ctx, &plane_bindings, "sweep")?;
        let output = FrameTarget::new(ctx, width, height, "sweep frame")?;
        let env_params = Buffer::uniform::<EnvParams>(ctx, "environment params")?;
        let mut composite_bindings = sampled.clone();
        composite_bindings.push(Binding::StorageImage(&output.image));
        composite_bindings.push(Binding::Texture(env.map, sampler));
        composite_bindings.push(Binding::Texture(env.sat, sampler));
        composite_bindings.push(Binding::Uniform(&env_params));
        let composite_set = DescriptorSet::new(ctx, &composite_bindings, "sweep composite")?;
        let mut setup_bindings: Vec<Binding> = common.to_vec();
        for s in &states {
            setup_bindings.push(Binding::StorageImage(&s.image));
        }
        for irr in &irradiance {
            setup_bindings.push(Binding::StorageImage(&irr.image));
        }
        for r in &rays {
            setup_bindings.push(Binding::StorageImage(&r.image));
        }
        let setup_set = DescriptorSet::new(ctx, &setup_bindings, "sweep setup")?;

        let setup =
            ComputePipeline::new(ctx, shaders::SWEEP_SETUP_COMP, &setup_set, 0, "sweep setup")?;
        let floor = GraphicsPipeline::new(
            ctx,
            &GraphicsDesc::fullscreen(
                shaders::FULLSCREEN_VERT,
                shaders::SWEEP_FLOOR_FRAG,
                &render_pass,
                &sweep_set,
                std::mem::size_of::<PlanePush>() as u32,
            ),
            "sweep floor plane",
        )?;
        let forward_capable = ctx.info().large_points && ctx.info().fragment_atomics;
        let forward = if forward_capable {
            let largest_point = ctx.info().limits.point_size_range[1];
            Some(ForwardPipelines {
                splat: GraphicsPipeline::new(
                    ctx,
                    &GraphicsDesc {
                        primitives: Primitives::AdditivePoints,
                        ..GraphicsDesc::fullscreen(
                            shaders::LIGHT_SPLAT_VERT,
                            shaders::LIGHT_SPLAT_FRAG,
                            &splat_pass,
                            &sweep_set,
                            std::mem::size_of::<PlanePush>() as u32,
                        )
                    },
                    "light splat",
                )?,
                max_half_width: MAX_SPLAT_HALF_WIDTH.min(((largest_point - 2.0) / 2.0).floor()),
            })
        } else {
            None
        };
        let all = PlanePipelines::new(
            ctx,
            [&render_pass, &light_pass, &view_pass],
            &sweep_set,
            Features::ALL.constants(have_gradient),
            forward_capable,
        )?;
        let planes = HashMap::from([(Features::ALL, all)]);
        let composite = ComputePipeline::new(
            ctx,
            shaders::SWEEP_COMPOSITE_COMP,
            &composite_set,
            4,
            "sweep composite",
        )?;
        Ok(Self {
            width,
            height,
            params,
            states,
            render_pass,
            framebuffers,
            sweep_set,
            setup_set,
            composite_set,
            setup,
            planes,
            have_gradient,
            floor,
            forward,
            irradiance,
            rays,
            rays_per_pixel,
            splat_pass,
            splat_framebuffers,
            light_pass,
            light_framebuffers,
            view_pass,
            view_framebuffers,
            counters,
            composite,
            output,
            env_params,
        })
    }

    /// Make the plane pipelines for `features` if this pass has none yet (once per
    /// feature set: a few hundred ms of shader compilation on lavapipe).
    pub(crate) fn ensure_planes(&mut self, ctx: &Context, features: Features) -> Result<()> {
        if !self.planes.contains_key(&features) {
            let planes = PlanePipelines::new(
                ctx,
                [&self.render_pass, &self.light_pass, &self.view_pass],
                &self.sweep_set,
                features.constants(self.have_gradient),
                self.forward.is_some(),
            )?;
            self.planes.insert(features, planes);
        }
        Ok(())
    }

    /// The same layers of all six state images, bound for the same use.
    pub(crate) fn state_layers(
        &self,
        layers: std::ops::Range<u32>,
        access: Access,
    ) -> Vec<(&Image, std::ops::Range<u32>, Access)> {
        self.states
            .iter()
            .map(|s| (&s.image, layers.clone(), access))
            .collect()
    }

    /// Both layers of every image the setup writes (state, irradiance, rays), for `access`.
    pub(crate) fn every_layer(
        &self,
        access: Access,
    ) -> Vec<(&Image, std::ops::Range<u32>, Access)> {
        self.states
            .iter()
            .chain(&self.irradiance)
            .chain(&self.rays)
            .map(|s| (&s.image, 0..2, access))
            .collect()
    }

    /// State-buffer traffic of one plane (see [`SweepStats::bytes_per_plane`]).
    pub fn bytes_per_plane(&self, soft: bool, specular: bool) -> u64 {
        let pixels = self.width as u64 * self.height as u64;
        // Attachment loads (6) and writes (6); sampled: light direction here (1), light
        // colour + direction at the back-projected point (2 per tap), viewing-ray state
        // (4), light colour at the ray (1), light direction at the ray for specular (1).
        let taps = if soft { 3 } else { 1 };
        let reads = 6 + 1 + 2 * taps + 4 + 1 + u64::from(specular);
        pixels * (reads + 6) * STATE_BYTES_PER_PIXEL
    }
}
