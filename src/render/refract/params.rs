//! The sweep's GPU parameter blocks (std140 and push-constant mirrors of glsl/sweep_*.glsl,
//! checked against the SPIR-V by the tests below) and the forward transport's ray grid.

use super::*;

/// std140 mirror of `SweepParams` in glsl/sweep_common.glsl.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct SweepParams {
    pub(crate) view_to_tex: [f32; 16],
    pub(crate) view_to_world: [f32; 16],
    pub(crate) camera: [f32; 4],
    pub(crate) planes: [f32; 4],
    pub(crate) light_dir: [f32; 4],
    pub(crate) light_colour: [f32; 4],
    pub(crate) volume_dims: [f32; 4],
    pub(crate) specular: [f32; 4],
    pub(crate) clip: [f32; 4],
    pub(crate) background: [f32; 4],
    pub(crate) refraction: [f32; 4],
    pub(crate) light_grid: [f32; 4],
    pub(crate) transport: [f32; 4],
    pub(crate) light_rays: [f32; 4],
    pub(crate) max_gain: f32,
    pub(crate) termination_alpha: f32,
    pub(crate) unlit: u32,
    pub(crate) pad0: u32,
    pub(crate) ambient: [f32; 4],
}

/// std140 mirror of `EnvParams` in glsl/sweep_composite.comp.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct EnvParams {
    pub(crate) info: [f32; 4],
    pub(crate) mean: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct PlanePush {
    pub(crate) plane: u32,
    pub(crate) read_layer: u32,
    pub(crate) depth: f32,
    pub(crate) pad: u32,
    /// The polygon the plane's draw covers, in normalised device coordinates
    /// (glsl/sweep_region.vert; region.rs `RegionPolygon`); the other draws ignore it.
    pub(crate) region: [[f32; 2]; 8],
}

/// Push constants of every pipeline of the compute sweep (glsl/sweep_plane_io.glsl): one
/// size for all, so that switching between them keeps the descriptor set bound.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct ComputePush {
    pub(crate) plane: u32,
    pub(crate) read_layer: u32,
    pub(crate) depth: f32,
    /// The compute splat's fixed-point unit (glsl/light_splat_fixed.glsl).
    pub(crate) unit: f32,
    /// The first pixel (or ray texel) the dispatch covers, and how many. The splat's
    /// per-ray dispatches: the first grid row they deposit (y) and how many rows.
    pub(crate) origin: [i32; 2],
    pub(crate) extent: [i32; 2],
    /// The light rays' pass: the texel rows of the ray images the previous plane moved,
    /// [lo, end) in 16 bits each (the `rays` lever, ray_rows.rs): a row outside them
    /// still holds its launch state (glsl/sweep_plane.glsl, `light_ray_plane`).
    pub(crate) pad: u32,
}

/// Push constants of the composite (glsl/sweep_composite.comp).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct CompositePush {
    /// The layer the last plane wrote.
    pub(crate) layer: u32,
    /// 1: the first face's reflection sees the volume (`--reflections volume`).
    pub(crate) volume_reflections: u32,
    /// The light record's stride in planes.
    pub(crate) record_stride: u32,
    /// 1: the smoothed gradient volume is bound (binding 15).
    pub(crate) have_gradient: u32,
    /// 1: the light is the eikonal transport's light volume (binding 16), not the planes'.
    pub(crate) light_from_volume: u32,
}

/// The forward transport's grid of light rays on the launch plane (one spacing before
/// plane 0): (x, y of the grid's corner, cell width, cell height) in view units, and its
/// columns and rows. Every point of every plane's view rectangle traced back along the
/// (unrefracted) light lands inside it, so no plane has a region no ray could reach; two
/// cells of margin on each side keep the splats at the border whole. The cells are
/// `spacing` times the pixel pitch of plane 0 (where pixels are smallest; at 1 the
/// irradiance is resolved at least as finely as the screen), unless that takes more than
/// `budget` rays: oblique light seen through a narrow view needs rays over several screen
/// heights (the light reaching the deepest plane comes from far aside), and then the
/// pitch grows evenly.
pub(crate) fn light_grid(
    planes: &Planes,
    light: Vec3,
    tan_half: f32,
    aspect: f32,
    size: [u32; 2],
    spacing: f32,
    budget: u64,
) -> ([f32; 4], [u32; 2]) {
    let launch = planes.first_depth - planes.spacing;
    let last = planes.depth(planes.count.saturating_sub(1));
    let (mut lo, mut hi) = (
        glam::Vec2::splat(f32::INFINITY),
        glam::Vec2::splat(f32::NEG_INFINITY),
    );
    let slope = glam::Vec2::new(light.x, light.y) / light.z;
    for z in [launch, last] {
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
            let corner = glam::Vec2::new(sx * z * tan_half * aspect, sy * z * tan_half);
            let back = corner - slope * (z - launch);
            lo = lo.min(back);
            hi = hi.max(back);
        }
    }
    let pitch = spacing * plane0_pixel_pitch(planes, tan_half, size);
    let extent = hi - lo;
    let mut n = (extent / pitch).ceil() + 4.0;
    let count = n.x as f64 * n.y as f64;
    if count > budget as f64 {
        n = (n * (budget as f64 / count).sqrt() as f32).floor();
    }
    let mut n = n.max(glam::Vec2::splat(5.0));
    // The floor of five per side can take a thin grid (a 1024 × 1 image, a narrow field of
    // view) past the budget: its long side then gives way (the budget is at least 25).
    if n.x as f64 * n.y as f64 > budget as f64 {
        if n.x >= n.y {
            n.x = (budget as f64 / n.y as f64).floor().max(5.0) as f32;
        } else {
            n.y = (budget as f64 / n.x as f64).floor().max(5.0) as f32;
        }
    }
    let cell = extent / (n - 4.0);
    let corner = lo - 2.0 * cell;
    (
        [corner.x, corner.y, cell.x, cell.y],
        [n.x as u32, n.y as u32],
    )
}

/// The height of a pixel on plane 0, view units (pixels are square).
pub(crate) fn plane0_pixel_pitch(planes: &Planes, tan_half: f32, size: [u32; 2]) -> f32 {
    2.0 * planes.first_depth * tan_half / size[1] as f32
}

/// Softness as diffusion between neighbouring light rays: the weight each ray hands to each
/// of its 4 neighbours `stride` rays away, so that every plane adds the per-axis variance
/// of the thesis' soft-shadow kernel (3 taps on a circle of radius `radius` world units:
/// radius²/2) for rays `cell` world units apart. The weight stays at most 0.2 (a larger
/// variance takes a longer stride), keeping every ray's own share positive.
pub(crate) fn diffusion(radius: f32, cell: f32) -> (f32, u32) {
    if !(radius > 0.0 && cell > 0.0) {
        return (0.0, 1);
    }
    // Per axis, the 5-point exchange adds 2 w stride² cells² of variance.
    let cells2 = 0.5 * radius * radius / (cell * cell);
    let w_stride2 = 0.5 * cells2;
    let stride = (w_stride2 / 0.2).sqrt().ceil().max(1.0);
    (w_stride2 / (stride * stride), stride as u32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::spirv::check_block;

    fn sweep_params_layout() -> Vec<(&'static str, usize, usize)> {
        crate::host_layout!(SweepParams {
            view_to_tex,
            view_to_world,
            camera,
            planes,
            light_dir,
            light_colour,
            volume_dims,
            specular,
            clip,
            background,
            refraction,
            light_grid,
            transport,
            light_rays,
            max_gain,
            termination_alpha,
            unlit,
            pad0,
            ambient,
        })
    }

    /// The std140 and push-constant mirrors against the blocks glslang laid out.
    #[test]
    fn host_structs_match_the_shaders_blocks() {
        let params = sweep_params_layout();
        let size = std::mem::size_of::<SweepParams>();
        for spirv in [
            shaders::SWEEP_FRAG,
            shaders::SWEEP_SETUP_COMP,
            shaders::SWEEP_COMPOSITE_COMP,
            shaders::SWEEP_VIEW_FORWARD_FRAG,
        ] {
            check_block(spirv, "SweepParams", &params, size, true).unwrap();
        }
        let env = crate::host_layout!(EnvParams { info, mean });
        let size = std::mem::size_of::<EnvParams>();
        check_block(shaders::SWEEP_COMPOSITE_COMP, "EnvParams", &env, size, true).unwrap();
        let push = crate::host_layout!(PlanePush {
            plane,
            read_layer,
            depth,
            pad,
            region
        });
        let size = std::mem::size_of::<PlanePush>();
        for spirv in [
            shaders::SWEEP_FRAG,
            shaders::SWEEP_LIGHT_FORWARD_FRAG,
            shaders::SWEEP_VIEW_FORWARD_FRAG,
            shaders::SWEEP_REGION_VERT,
            shaders::LIGHT_SPLAT_VERT,
            shaders::LIGHT_SPLAT_BOXES_VERT,
            shaders::LIGHT_SPLAT_GROUPS_VERT,
            shaders::LIGHT_SPLAT_GROUPS_BOXES_VERT,
            // (LIGHT_SPLAT_GROUP_RAYS_VERT reads no push constant: its block is compiled out.)
        ] {
            check_block(spirv, "Push", &push, size, false).unwrap();
        }
        let push = crate::host_layout!(ComputePush {
            plane,
            read_layer,
            depth,
            unit,
            origin,
            extent,
            pad
        });
        let size = std::mem::size_of::<ComputePush>();
        for spirv in [
            shaders::SWEEP_COMP,
            shaders::SWEEP_LIGHT_FORWARD_COMP,
            shaders::SWEEP_VIEW_FORWARD_COMP,
            shaders::SWEEP_FLOOR_COMP,
            shaders::SWEEP_DEPOSIT_COMP,
            shaders::SWEEP_BIN_FILL_COMP,
            shaders::SWEEP_SCATTER_COMP,
        ] {
            check_block(spirv, "Push", &push, size, false).unwrap();
        }
        check_block(
            shaders::SWEEP_COMP,
            "SweepParams",
            &params,
            size_of_params(),
            true,
        )
        .unwrap();
    }

    fn size_of_params() -> usize {
        std::mem::size_of::<SweepParams>()
    }

    /// The check fails when a host field is missing or moved (it can fail).
    #[test]
    fn a_moved_field_fails_the_block_check() {
        let mut params = sweep_params_layout();
        let size = std::mem::size_of::<SweepParams>();
        params.swap(2, 3);
        params[2].0 = "camera";
        params[3].0 = "planes";
        params[2].1 += 16;
        let e = check_block(shaders::SWEEP_FRAG, "SweepParams", &params, size, true);
        assert!(e.unwrap_err().to_string().contains("'camera'"));
        params.retain(|(name, _, _)| *name != "light_rays");
        let e = check_block(shaders::SWEEP_FRAG, "SweepParams", &params, size, true);
        assert!(e.unwrap_err().to_string().contains("light_rays"));
    }
}
