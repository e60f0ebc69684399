//! The ambient-scattering model (`--model ambient`, src/render/ambient) rendered on the GPU
//! against what physics says it must do: where nothing scatters twice (albedo → 0) and the
//! ambient sphere is small, it is single scattering (the closed-form integral of
//! tests/common, and the single model itself); light crossing empty space arrives
//! undimmed whatever the radius (the tube's transmission is 1 there: the paper's eq. 16
//! would dim it by p_HG(0)/4π per step); several lights add up (the model is linear in
//! its lights: one radiance-cache channel each, point and directional); and a change
//! rebuilds only the caches that depend on it.

mod common;

use common::{constant_tf, f32_volume, face_on, single_scattering_block, with_context};
use glam::Vec3;
use refrakt::light::LightSource;
use refrakt::render::ambient::table::{AmbientTable, TableParams};
use refrakt::render::ambient::{AmbientOptions, CACHE_SCOPE, EXTINCTION_SCOPE};
use refrakt::render::{
    Light, Model, RenderOptions, Renderer, ScatterOptions, SweepOptions, SCATTER_ALBEDO, SCATTER_G,
};

/// A small table (seconds to build) for `albedo`.
fn small_table(albedo: f32) -> AmbientTable {
    let params = TableParams {
        albedo,
        theta_bins: 9,
        s_bins: 12,
        g_bins: 5,
        paths: 64,
        ..Default::default()
    };
    AmbientTable::build(&params, 0, &|_, _| {}).unwrap()
}

fn options(towards: Vec3, g: f32, albedo: f32, radius: f32, size: u32) -> RenderOptions {
    let mut opts = RenderOptions {
        width: size,
        height: size,
        background: [0.0, 0.0, 0.0, 1.0],
        lights: vec![Light {
            source: refrakt::light::LightSource::Directional {
                towards: towards.normalize(),
            },
            colour: [1.0; 3],
            softness: 0.0,
        }],
        sweep: SweepOptions {
            ..Default::default()
        },
        ..Default::default()
    };
    ScatterOptions { g, albedo }.set_in(&mut opts).unwrap();
    AmbientOptions { radius }.set_in(&mut opts).unwrap();
    opts
}

#[test]
fn without_multiple_scattering_a_small_sphere_is_single_scattering() {
    with_context(|ctx| {
        let n = 33u32;
        let camera = face_on(3.0, 10.0);
        let albedo = 0.02;
        let mut renderer =
            Renderer::new(ctx, &f32_volume(n, |_| 1.0), &constant_tf([1.0; 3], 0.1)).unwrap();
        renderer.set_ambient_table(&small_table(albedo)).unwrap();
        for (towards, g) in [([0.0, 1.0, 1.0], 0.5f64), ([0.0, 0.3, 1.0], -0.3)] {
            let t = Vec3::from(towards.map(|c: f64| c as f32)).normalize();
            let opts = options(t, g as f32, albedo, 0.5, 33);
            let got = renderer
                .render(Model::Ambient, &camera, &opts)
                .unwrap()
                .pixel(16, 16)[1] as f64;
            let k = -(0.9f64).ln() * n as f64;
            let want =
                albedo as f64 * single_scattering_block(k, 0.5, [0.0, t.y as f64, t.z as f64], g);
            eprintln!(
                "towards {towards:?} g {g}: ambient {got:.6}, single-scattering integral {want:.6} ({:+.2} %)",
                100.0 * (got / want - 1.0)
            );
            // 3 %: the radiance cache is at half the volume's resolution, so within a voxel
            // of the face the light is interpolated towards its value a voxel inside
            // (measured ~2 % of this integral, which those first voxels weigh most).
            assert!(
                (got - want).abs() <= 0.03 * want,
                "light {towards:?}, g {g}: ambient {got}, single-scattering integral {want}"
            );
        }
    });
}

#[test]
fn light_crosses_empty_space_undimmed_at_every_radius() {
    with_context(|ctx| {
        // A thin, faint sheet at the bottom of an otherwise empty box, lit from above at an
        // angle: the light crosses ~30 voxels of nothing before it. Faint, so that the
        // ambient sphere's own attenuation of the light it scatters (e^(-r σ̃), which
        // single scattering does not have) stays below 1 % even at radius 12.
        let n = 40u32;
        let sheet = f32_volume(n, |p| if p[1] < 0.15 { 1.0 } else { 0.0 });
        // Nothing below the sheet's value: the empty part stays empty.
        let tf = refrakt::transfer::TransferFunctions::parse(
            "colour = [[0.0, 1, 1, 1]]\nopacity = [[0.0, 0.0], [0.45, 0.0], [0.55, 0.003], [1.0, 0.003]]\n",
            "sheet",
        )
        .unwrap();
        let mut renderer = Renderer::new(ctx, &sheet, &tf).unwrap();
        let albedo = 0.02;
        renderer.set_ambient_table(&small_table(albedo)).unwrap();
        let camera = refrakt::render::Camera {
            elevation: 60.0,
            ..face_on(3.0, 12.0)
        };
        let towards = Vec3::new(0.3, 1.0, 0.4);
        let single = renderer
            .render(
                Model::Single,
                &camera,
                &options(towards, 0.0, albedo, 1.0, 32),
            )
            .unwrap();
        let s = single.pixel(16, 20)[1] as f64;
        assert!(s > 1e-4, "the sheet is lit in the single model: {s}");
        for radius in [1.0, 4.0, 12.0] {
            let frame = renderer
                .render(
                    Model::Ambient,
                    &camera,
                    &options(towards, 0.0, albedo, radius, 32),
                )
                .unwrap();
            let a = frame.pixel(16, 20)[1] as f64;
            eprintln!(
                "radius {radius}: ambient {a:.6}, single {s:.6} ({:+.2} %)",
                100.0 * (a / s - 1.0)
            );
            assert!(
                (a - s).abs() <= 0.02 * s,
                "radius {radius}: the sheet under empty space gets {a}, single scattering {s}"
            );
        }
    });
}

#[test]
fn several_lights_add_up() {
    with_context(|ctx| {
        // A lumpy medium so that each light's shadows differ.
        let n = 24u32;
        let vol = f32_volume(n, |p| {
            let c = [p[0] - 0.35, p[1] - 0.55, p[2] - 0.5];
            if c[0] * c[0] + c[1] * c[1] + c[2] * c[2] < 0.04 {
                1.0
            } else {
                0.3
            }
        });
        let tf = refrakt::transfer::TransferFunctions::parse(
            "colour = [[0.0, 1, 0.8, 0.6]]\nopacity = [[0.0, 0.0], [0.2, 0.02], [1.0, 0.3]]\n",
            "lumps",
        )
        .unwrap();
        let mut renderer = Renderer::new(ctx, &vol, &tf).unwrap();
        renderer.set_ambient_table(&small_table(0.9)).unwrap();
        let camera = refrakt::render::Camera {
            azimuth: 20.0,
            elevation: 25.0,
            ..face_on(3.0, 20.0)
        };
        let main = Vec3::new(0.2, 1.0, 0.5);
        let point = Light {
            source: LightSource::Point {
                position: Vec3::new(-0.8, 0.3, 0.9),
            },
            ..Light::directional(Vec3::Y, [0.2, 0.5, 1.5])
        };
        let side = Light::directional(Vec3::new(1.0, -0.2, 0.3), [1.0, 0.3, 0.1]);
        let mut render = |main_colour: [f32; 3], extra: Vec<Light>| {
            let mut o = options(main, 0.4, 0.9, 3.0, 24);
            o.light_mut().colour = main_colour;
            o.lights.extend(extra);
            renderer_frame(&mut renderer, &camera, &o)
        };
        let dark = render([0.0; 3], vec![]);
        let a = render([1.0; 3], vec![]);
        let b = render([0.0; 3], vec![point]);
        let c = render([0.0; 3], vec![side]);
        let all = render([1.0; 3], vec![point, side]);
        let (mut max_err, mut max_sum, mut max_b, mut max_c) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for i in 0..all.len() {
            for ch in 0..3 {
                let sum = a[i][ch] + b[i][ch] + c[i][ch] - 2.0 * dark[i][ch];
                max_err = max_err.max((all[i][ch] - sum).abs());
                max_sum = max_sum.max(sum);
                max_b = max_b.max(b[i][ch] - dark[i][ch]);
                max_c = max_c.max(c[i][ch] - dark[i][ch]);
            }
        }
        eprintln!(
            "max |all - sum| {max_err:e} of {max_sum}; point light alone {max_b}, side {max_c}"
        );
        assert!(
            max_b > 0.02 && max_c > 0.02,
            "each extra light lights something: {max_b}, {max_c}"
        );
        assert!(
            max_err <= 1e-4 * max_sum,
            "lights do not add up: {max_err} of {max_sum}"
        );
        // A light gives the same image in any slot: the side light as the main light.
        let mut o = options(Vec3::new(1.0, -0.2, 0.3), 0.4, 0.9, 3.0, 24);
        o.light_mut().colour = side.colour;
        let side_as_main = renderer_frame(&mut renderer, &camera, &o);
        // The largest |(with − dark) − alone| over pixels and channels: a light's own
        // contribution in one slot against the same light alone in slot 0.
        let slot_error = |with: &[[f32; 4]], alone: &[[f32; 4]]| {
            (0..with.len())
                .flat_map(|i| (0..3).map(move |ch| (i, ch)))
                .map(|(i, ch)| (with[i][ch] - dark[i][ch] - alone[i][ch]).abs())
                .fold(0.0f32, f32::max)
        };
        let slot_err = slot_error(&c, &side_as_main);
        assert!(
            slot_err <= 1e-4 * max_c,
            "the side light in slot 2 vs slot 0: {slot_err}"
        );
        // And a point light as the main light (one light type: any slot takes either).
        let mut o = options(main, 0.4, 0.9, 3.0, 24);
        o.lights = vec![point];
        let point_as_main = renderer_frame(&mut renderer, &camera, &o);
        let point_err = slot_error(&b, &point_as_main);
        assert!(
            point_err <= 1e-4 * max_b,
            "the point light in slot 1 vs slot 0: {point_err}"
        );
        // The point light's colour lands in its own channel: blue over red where it alone
        // shines.
        let bluest = (0..b.len())
            .max_by(|&i, &j| b[i][2].total_cmp(&b[j][2]))
            .unwrap();
        assert!(
            b[bluest][2] > 2.0 * b[bluest][0],
            "point light colour {:?}",
            b[bluest]
        );
    });
}

fn renderer_frame(
    renderer: &mut Renderer,
    camera: &refrakt::render::Camera,
    opts: &RenderOptions,
) -> Vec<[f32; 4]> {
    renderer
        .render(Model::Ambient, camera, opts)
        .unwrap()
        .pixels
}

#[test]
fn a_change_rebuilds_only_what_depends_on_it() {
    with_context(|ctx| {
        let n = 16u32;
        let mut renderer =
            Renderer::new(ctx, &f32_volume(n, |p| p[0]), &constant_tf([1.0; 3], 0.1)).unwrap();
        renderer.set_ambient_table(&small_table(0.9)).unwrap();
        if !ctx.info().timestamps {
            eprintln!("no timestamps on this device: nothing to check");
            return;
        }
        let camera = face_on(3.0, 20.0);
        let base = options(Vec3::new(0.0, 1.0, 1.0), 0.3, 0.9, 2.0, 16);
        let rebuilt = |r: &mut Renderer, camera: &refrakt::render::Camera, o: &RenderOptions| {
            let t = r.render(Model::Ambient, camera, o).unwrap().timings;
            (
                t.get(EXTINCTION_SCOPE).is_some(),
                t.get(CACHE_SCOPE).is_some(),
                t.get(refrakt::render::extinction::EXTINCTION_SCOPE)
                    .is_some(),
            )
        };
        assert_eq!(
            rebuilt(&mut renderer, &camera, &base),
            (true, true, true),
            "first frame"
        );
        assert_eq!(
            rebuilt(&mut renderer, &camera, &base),
            (false, false, false),
            "same frame"
        );
        let moved = face_on(2.5, 25.0);
        assert_eq!(
            rebuilt(&mut renderer, &moved, &base),
            (false, false, false),
            "camera"
        );
        let mut o = base.clone();
        o.light_mut()
            .set_towards(Vec3::new(0.3, 1.0, 1.0).normalize());
        assert_eq!(
            rebuilt(&mut renderer, &camera, &o),
            (false, true, false),
            "light"
        );
        o.models.set(&SCATTER_G, 0.5).unwrap();
        assert_eq!(
            rebuilt(&mut renderer, &camera, &o),
            (false, true, false),
            "phase function"
        );
        o.lights.push("point:0,1,1".parse().unwrap());
        assert_eq!(
            rebuilt(&mut renderer, &camera, &o),
            (false, true, false),
            "another light"
        );
        AmbientOptions { radius: 3.0 }.set_in(&mut o).unwrap();
        assert_eq!(
            rebuilt(&mut renderer, &camera, &o),
            (true, true, false),
            "radius"
        );
        renderer
            .set_transfer_functions(&constant_tf([1.0; 3], 0.2))
            .unwrap();
        assert_eq!(
            rebuilt(&mut renderer, &camera, &o),
            (true, true, true),
            "transfer functions"
        );
        // The albedo is the table's: another albedo is refused while this table is set.
        o.models.set(&SCATTER_ALBEDO, 0.5).unwrap();
        let e = renderer
            .render(Model::Ambient, &camera, &o)
            .unwrap_err()
            .to_string();
        assert!(e.contains("albedo"), "{e}");
    });
}

#[test]
fn a_lit_floor_has_no_stripes_at_any_radius() {
    with_context(|ctx| {
        // An opaque slab lit obliquely, the light entering the box through its side so the
        // tubes' lengths vary across the floor: every point of the top sees the same
        // light, so its image must be smooth. Tube marching on a grid fixed at the light
        // (the paper's eq. 17) modulates it with period 2r (measured: a second difference
        // of 2.2 % of the floor); each voxel's own tube does not (0.05 %).
        let n = 48u32;
        let floor = f32_volume(n, |p| if p[1] < 0.3 { 1.0 } else { 0.0 });
        let tf = refrakt::transfer::TransferFunctions::parse(
            "colour = [[0.0, 1, 1, 1]]\nopacity = [[0.0, 0.0], [0.45, 0.0], [0.55, 0.6], [1.0, 0.6]]\n",
            "floor",
        )
        .unwrap();
        let mut renderer = Renderer::new(ctx, &floor, &tf).unwrap();
        renderer.set_ambient_table(&small_table(0.9)).unwrap();
        let camera = refrakt::render::Camera {
            elevation: 89.0,
            ..face_on(3.0, 12.0)
        };
        for radius in [2.0, 5.0] {
            let o = options(Vec3::new(1.0, 0.7, 0.3), 0.0, 0.9, radius, 48);
            let f = renderer.render(Model::Ambient, &camera, &o).unwrap();
            // Smooth (the view's obliquity and the box's faces make a gentle dome) but
            // without steps or stripes: no large second difference anywhere on the top.
            let px = |x: u32, y: u32| f.pixel(x, y)[1] as f64;
            let (mut mean, mut count, mut worst) = (0.0, 0.0, (0.0f64, 0u32, 0u32));
            for y in 6..42 {
                for x in 6..42 {
                    mean += px(x, y);
                    count += 1.0;
                    let dx = (px(x - 1, y) - 2.0 * px(x, y) + px(x + 1, y)).abs();
                    let dy = (px(x, y - 1) - 2.0 * px(x, y) + px(x, y + 1)).abs();
                    if dx.max(dy) > worst.0 {
                        worst = (dx.max(dy), x, y);
                    }
                }
            }
            mean /= count;
            eprintln!(
                "radius {radius}: floor {mean:.5}, largest second difference {:.2e} at {:?}",
                worst.0,
                (worst.1, worst.2)
            );
            assert!(mean > 0.01, "the floor is lit: {mean}");
            assert!(
                worst.0 <= 0.003 * mean,
                "radius {radius}: the floor's top has a step or stripe of {} at pixel {:?} (mean {mean})",
                worst.0,
                (worst.1, worst.2)
            );
        }
    });
}
