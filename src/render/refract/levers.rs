//! The sweep's speed levers (issue 16): each a switch between the plain implementation
//! and a faster one that renders the same image (within stated bounds, tested), so that a
//! performance engineer can time and compare them in one process (`refrakt bench
//! variants`) and pick any combination from the command line (`--variant`).

use std::fmt;

use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};

/// Which pixels each plane shades.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Region {
    /// Every pixel of the viewport on every plane (the thesis' full-screen quad).
    Full,
    /// Plane i shades only the bounding rectangle of the screen projection of the part of
    /// the volume box between the first plane and plane i, widened by a margin: a pixel
    /// outside it has never seen the volume, so its state is still the setup's (a
    /// straight camera ray, the unattenuated light).
    Rect,
    /// The rectangle cut by the diagonals of the same box points' projection (x + y and
    /// x − y bounds, region.rs `RegionPolygon`): the fragment path draws that octagon, the
    /// compute path dispatches over the rectangle (the same pixels as `Rect` there). The
    /// same argument makes it exact: the octagons only grow, and a pixel outside has
    /// never seen the box.
    Octagon,
}

/// How the forward transport's light rays deposit their flux on a plane (both give the same
/// deposits, light_splat_ray.glsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Splat {
    /// One point sprite per ray, blended additively into two RGBA32F attachments.
    Raster,
    /// One point sprite per 2 x 2 rays whose deposits fit within
    /// `limits::SPLAT_GROUP_SPAN` pixels, a sprite per ray for the others (listed in
    /// order by a compute pass that also computes the deposits, and drawn indirectly):
    /// the same deposits with a quarter of the points, summed in another order
    /// (glsl/light_splat_groups.glsl). For lavapipe, whose vertex stage runs on one thread.
    Groups,
    /// One compute invocation per ray adding 32.32 fixed-point values with integer
    /// atomics, then a resolve into the irradiance images: order-independent sums, so
    /// still bit-reproducible frame to frame.
    Compute,
}

/// What a forward light ray deposits on a plane (glsl/light_splat_ray.glsl). Not a speed
/// lever like the others: the two render different images. `Boxes` is still the default
/// (and [`Levers::REFERENCE`]'s) for its cost: on lavapipe `Cells` took 4.2-4.5 x the
/// frame on the default fragment path and 1.34-1.38 x on the compute path, on an H100
/// 1.7-2.4 x (docs/NOTES.md, "Light as a wavefront", remeasured 2026-11-29). Both stay
/// selectable so that they can be timed and compared in one process
/// (`bench variants --variant deposit=cells`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Deposit {
    /// The wavefront (issue 32): each cell of four neighbouring rays spreads its flux
    /// over the two triangles it spans on the plane, exact area coverage per pixel, so
    /// irradiance = flux / area by construction.
    Cells,
    /// Each ray spreads its own flux over a box its cell's size centred on itself (the
    /// deposit before issue 32: a lattice where rays are sparser than pixels).
    Boxes,
}

impl Deposit {
    fn name(self) -> &'static str {
        match self {
            Deposit::Cells => "cells",
            Deposit::Boxes => "boxes",
        }
    }
}

/// How the compute sweep's splat sums the light rays' deposits (issue 31): every way adds
/// the same 32.32 fixed-point values as 64-bit integers, so all give the same irradiance
/// bit for bit; only their speed differs. Measured on an H100
/// (docs/BENCH.md, "the splat rebuilt"): pairs 436 against 531 ms on the supernova row,
/// 157 against 205 ms on the default scene at 768², but 530 against 474 ms on the piggy
/// bank.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Gather {
    /// One invocation per (ray, pixel) pair where a deposit lands, adding into the tile's
    /// sums in shared memory with integer atomics.
    Pairs,
    /// One invocation per pixel, looping over every ray listed for its tile and summing
    /// in registers (glsl/sweep_gather_pixels.comp: a subgroup evaluates a deposit for
    /// all its pixels where any of them needs it).
    Pixels,
    /// No bins: each workgroup of 8 × 8 neighbouring rays adds its deposits into a tile
    /// of pixels in shared memory and then the tile into the plane's sums with global
    /// integer atomics, one per pixel and channel (glsl/sweep_scatter.comp); two
    /// dispatches a plane instead of five.
    Blocks,
}

impl Gather {
    fn name(self) -> &'static str {
        match self {
            Gather::Pairs => "pairs",
            Gather::Pixels => "pixels",
            Gather::Blocks => "blocks",
        }
    }
}

/// How the planes of the sweep run (issue 31).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SweepPath {
    /// What measured fastest on this class of device ([`SweepPath::for_device`]).
    Auto,
    /// Full-screen draws into render passes (the thesis' design): every plane's passes
    /// are graphics draws, the state images colour attachments.
    Fragment,
    /// One compute dispatch per pass and plane on storage images (the same shaders,
    /// glsl/sweep_plane_io.glsl): on Hopper GPUs only 4 of 132 SMs run fragment
    /// shaders, dispatches use all of them. The forward transport's splat is the compute
    /// one (integer sums) on this path.
    Compute,
}

impl SweepPath {
    /// The path `Auto` stands for on a device of this type with this light transport
    /// (`forward`): what `bench variants` measured fastest there (docs/BENCH.md,
    /// "Compute or fragment"). CPU (lavapipe, measured): the backward transport as
    /// compute, the forward one as draws (its splat: the point sprites cost less there
    /// than either compute splat, whose integer sums llvmpipe runs slowly). GPUs: compute
    /// for both, from the structure of the hardware (draws run on the graphics-capable
    /// SMs only: 4 of 132 on an H100), until `scripts/gpu-bench.sh` has measured both.
    pub fn for_device(
        self,
        device_type: crate::vk::PhysicalDeviceType,
        forward: bool,
    ) -> SweepPath {
        match self {
            SweepPath::Auto if device_type == crate::vk::PhysicalDeviceType::CPU => {
                if forward {
                    SweepPath::Fragment
                } else {
                    SweepPath::Compute
                }
            }
            SweepPath::Auto => SweepPath::Compute,
            explicit => explicit,
        }
    }

    fn name(self) -> &'static str {
        match self {
            SweepPath::Auto => "auto",
            SweepPath::Fragment => "fragment",
            SweepPath::Compute => "compute",
        }
    }
}

/// One combination of the levers. `Levers::default()` (what renders unless told
/// otherwise) has every lever on that renders the plain implementation's image
/// ([`Levers::REFERENCE`], every lever off) within float rounding: region, arrays,
/// specialize. The field texture is off by default: it is another discretisation of ∇η
/// (render/field.rs) whose images differ visibly at some pixels of noisy media (measured
/// up to 0.71 of display range at single pixels, mean 2e-3 to 1e-2) for 1-5 % of the
/// frame on lavapipe (docs/BENCH.md). The fragment path's sprites are grouped by default
/// (`splat=groups`: the same deposits summed in another order, 0.61-0.85 x the splat's
/// time on lavapipe, measured). The compute splat is off by default: it renders the
/// raster splat's image within float rounding, but on lavapipe its integer atomics cost
/// more than the sprites (1.0-1.55x the frame, measured); it was built for GPUs, where
/// the sprites' blending into RGBA32F was 84 % of the forward sweep (H100, measured).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Levers {
    /// Which pixels each plane shades.
    pub region: Region,
    /// Value and ∇η from a precomputed field texture (one fetch) instead of central
    /// differences of the volume through the η transfer function (13 fetches).
    pub field: bool,
    /// State reads through one image-array view per buffer, indexed by the read layer,
    /// instead of a choice between two per-layer views (which llvmpipe fetches both of).
    pub arrays: bool,
    /// Specialization constants compile out what a frame does not use (specular,
    /// clipping, reflections, the backward soft-shadow kernel).
    pub specialize: bool,
    /// How the forward transport's light rays deposit their flux (the fragment path's;
    /// the compute path always splats with compute).
    pub splat: Splat,
    /// Draws or dispatches per plane.
    #[serde(default = "auto_path")]
    pub sweep: SweepPath,
    /// Clear space: a forward light ray crosses a plane step in one Snell sub-step
    /// instead of four where every value it can meet is the same, or clear with one η
    /// (render::value_ranges). The same ray within float rounding; rounding can still
    /// flip a ray at a threshold (total reflection, a grazing exit) where the optics
    /// are ill-conditioned.
    #[serde(default = "on")]
    pub clear: bool,
    /// What a forward light ray deposits (not a speed lever: see [`Deposit`]).
    #[serde(default = "boxes")]
    pub deposit: Deposit,
    /// How the compute sweep's splat sums a tile's deposits (the fragment path's splat
    /// is the `splat` lever's).
    #[serde(default = "pairs")]
    pub gather: Gather,
    /// `rays=needed`: each plane moves only the light rays' grid rows needed by then
    /// (they met the box or the viewing rays' light); a row joins with one straight step
    /// from the launch plane (render/refract/ray_rows.rs). The fragment path's grouped
    /// sprites and the compute path (whose splat then deposits the needed grid rows,
    /// since 2026-12-08); with the other sprites every ray moves on every plane. The same
    /// rays within float rounding (and, with softness, within 3e-7 of a penumbra's tail).
    #[serde(default = "on")]
    pub needed_rays: bool,
    /// `tile=on` (or `tile=H`, a halo of H pixels, 0-8; `on` is
    /// [`Levers::DEFAULT_TILE_HALO`]): the compute path's backward plane reads the
    /// previous plane's light from a workgroup tile of its 8 × 8 pixels and H around
    /// them in shared memory, and fetches only what falls outside (issue 31's compact
    /// state, item 2; glsl/sweep_plane_io.glsl). The same image bit for bit. Off by
    /// default: built for GPUs, not yet timed on one (`scripts/gpu-bench.sh` times it);
    /// on lavapipe it gains nothing (docs/NOTES.md, "The light's tile"). The fragment
    /// path and the forward transport do not read through it.
    #[serde(default)]
    pub tile: Option<u32>,
}

fn pairs() -> Gather {
    Gather::Pairs
}

fn boxes() -> Deposit {
    Deposit::Boxes
}

fn auto_path() -> SweepPath {
    SweepPath::Auto
}

fn on() -> bool {
    true
}

impl Default for Levers {
    fn default() -> Self {
        Self {
            region: Region::Octagon,
            field: false,
            arrays: true,
            specialize: true,
            splat: Splat::Groups,
            sweep: SweepPath::Auto,
            clear: true,
            deposit: Deposit::Boxes,
            gather: Gather::Pairs,
            needed_rays: true,
            tile: None,
        }
    }
}

impl Levers {
    /// Every lever off: the plain implementation.
    pub const REFERENCE: Levers = Levers {
        region: Region::Full,
        field: false,
        arrays: false,
        specialize: false,
        splat: Splat::Raster,
        sweep: SweepPath::Fragment,
        clear: false,
        deposit: Deposit::Boxes,
        gather: Gather::Pixels,
        needed_rays: false,
        tile: None,
    };

    /// The halo `tile=on` stands for: the backward step's origin lies a plane spacing
    /// along the light from the pixel and the soft kernel reaches `softness` reference
    /// steps around it, about a pixel each at the thesis' sizes.
    pub const DEFAULT_TILE_HALO: u32 = 4;

    /// The largest halo `tile=H` takes (a tile of 24 × 24 texels, 18 KiB of shared
    /// memory: more than the 16 KiB every device must offer, so the device's limit is
    /// checked when the pipelines are made).
    pub const MAX_TILE_HALO: u32 = 8;

    /// The keys of [`Levers::parse`], with their values, for help texts.
    pub const SYNTAX: &'static str =
        "region=full|rect|octagon, field=off|on, arrays=off|on, specialize=off|on, \
         splat=raster|groups|compute, sweep=auto|fragment|compute, clear=off|on, \
         deposit=cells|boxes, gather=pairs|pixels|blocks, rays=all|needed, tile=off|on|0-8";

    /// `default`, `reference`, or comma-separated `key=value` pairs applied to the
    /// default (e.g. `region=full,field=off`); a pair may also follow `reference,` to
    /// switch single levers on from the reference.
    pub fn parse(spec: &str) -> Result<Levers> {
        let spec = spec.trim();
        if spec.is_empty() {
            bail!(
                "empty variant: give `default`, `reference` or {}",
                Self::SYNTAX
            );
        }
        let mut levers = Levers::default();
        let mut keys: Vec<&str> = Vec::new();
        for (k, part) in spec.split(',').map(str::trim).enumerate() {
            match part {
                "default" if k == 0 => continue,
                "reference" if k == 0 => {
                    levers = Levers::REFERENCE;
                    continue;
                }
                "default" | "reference" => {
                    bail!("'{part}' can only start a variant (got '{spec}')")
                }
                _ => {}
            }
            let Some((key, value)) = part.split_once('=') else {
                bail!(
                    "'{part}' in variant '{spec}' is not key=value; the keys are {}",
                    Self::SYNTAX
                );
            };
            let (key, value) = (key.trim(), value.trim());
            // One value a lever: with two, which one was meant?
            if keys.contains(&key) {
                bail!("'{key}' is given twice in variant '{spec}'");
            }
            keys.push(key);
            let on = |value: &str| match value {
                "on" | "true" | "1" => Ok(true),
                "off" | "false" | "0" => Ok(false),
                _ => bail!("{key}={value}: expected on or off"),
            };
            match key {
                "region" => {
                    levers.region = match value {
                        "full" => Region::Full,
                        "rect" => Region::Rect,
                        "octagon" => Region::Octagon,
                        _ => bail!("region={value}: expected full, rect or octagon"),
                    }
                }
                "field" => levers.field = on(value)?,
                "arrays" => levers.arrays = on(value)?,
                "specialize" => levers.specialize = on(value)?,
                "clear" => levers.clear = on(value)?,
                "splat" => {
                    levers.splat = match value {
                        "raster" => Splat::Raster,
                        "groups" => Splat::Groups,
                        "compute" => Splat::Compute,
                        _ => bail!("splat={value}: expected raster, groups or compute"),
                    }
                }
                "deposit" => {
                    levers.deposit = match value {
                        "cells" => Deposit::Cells,
                        "boxes" => Deposit::Boxes,
                        _ => bail!("deposit={value}: expected cells or boxes"),
                    }
                }
                "gather" => {
                    levers.gather = match value {
                        "pairs" => Gather::Pairs,
                        "pixels" => Gather::Pixels,
                        "blocks" => Gather::Blocks,
                        _ => bail!("gather={value}: expected pairs, pixels or blocks"),
                    }
                }
                "rays" => {
                    levers.needed_rays = match value {
                        "all" => false,
                        "needed" => true,
                        _ => bail!("rays={value}: expected all or needed"),
                    }
                }
                "tile" => {
                    levers.tile = match value {
                        "off" => None,
                        "on" => Some(Self::DEFAULT_TILE_HALO),
                        _ => match value.parse::<u32>() {
                            Ok(h) if h <= Self::MAX_TILE_HALO => Some(h),
                            _ => bail!(
                                "tile={value}: expected off, on or a halo in pixels from 0 \
                                 to {}",
                                Self::MAX_TILE_HALO
                            ),
                        },
                    }
                }
                "sweep" => {
                    levers.sweep = match value {
                        "auto" => SweepPath::Auto,
                        "fragment" => SweepPath::Fragment,
                        "compute" => SweepPath::Compute,
                        _ => bail!("sweep={value}: expected auto, fragment or compute"),
                    }
                }
                _ => bail!(
                    "unknown lever '{key}' in variant '{spec}'; the keys are {}",
                    Self::SYNTAX
                ),
            }
        }
        Ok(levers)
    }

    /// Each lever flipped away from `self` in turn: the variants that attribute a
    /// combination's speed to its levers.
    pub fn each_flipped(self) -> Vec<Levers> {
        let mut out = Vec::new();
        let mut v = self;
        v.region = match self.region {
            Region::Full => Region::Octagon,
            Region::Rect | Region::Octagon => Region::Full,
        };
        out.push(v);
        // The octagon is the rectangle cut: time it against the rectangle too.
        if self.region == Region::Octagon {
            v.region = Region::Rect;
            out.push(v);
        }
        for flip in [
            |l: &mut Levers| l.field = !l.field,
            |l: &mut Levers| l.arrays = !l.arrays,
            |l: &mut Levers| l.specialize = !l.specialize,
            |l: &mut Levers| l.clear = !l.clear,
            |l: &mut Levers| l.needed_rays = !l.needed_rays,
            |l: &mut Levers| {
                l.splat = match l.splat {
                    Splat::Raster | Splat::Groups => Splat::Compute,
                    Splat::Compute => Splat::Raster,
                }
            },
        ] {
            let mut v = self;
            flip(&mut v);
            out.push(v);
        }
        // The path: the other explicit one, or from `auto` both (one of which is what
        // `auto` runs on the device at hand).
        let paths: &[SweepPath] = match self.sweep {
            SweepPath::Auto => &[SweepPath::Fragment, SweepPath::Compute],
            SweepPath::Fragment => &[SweepPath::Compute],
            SweepPath::Compute => &[SweepPath::Fragment],
        };
        for &sweep in paths {
            out.push(Levers { sweep, ..self });
        }
        out
    }
}

impl fmt::Display for Levers {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let on = |b: bool| if b { "on" } else { "off" };
        write!(
            f,
            "region={},field={},arrays={},specialize={},splat={},sweep={},clear={},deposit={},\
             gather={},rays={},tile={}",
            match self.region {
                Region::Full => "full",
                Region::Rect => "rect",
                Region::Octagon => "octagon",
            },
            on(self.field),
            on(self.arrays),
            on(self.specialize),
            match self.splat {
                Splat::Raster => "raster",
                Splat::Groups => "groups",
                Splat::Compute => "compute",
            },
            self.sweep.name(),
            on(self.clear),
            self.deposit.name(),
            self.gather.name(),
            if self.needed_rays { "needed" } else { "all" },
            match self.tile {
                None => "off".to_string(),
                Some(Self::DEFAULT_TILE_HALO) => "on".to_string(),
                Some(h) => h.to_string(),
            }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_round_trips_and_applies_to_the_default() {
        let all = [Region::Full, Region::Rect, Region::Octagon];
        for region in all {
            for bits in 0..96u32 {
                let l = Levers {
                    sweep: [SweepPath::Auto, SweepPath::Fragment, SweepPath::Compute]
                        [(bits / 16 % 3) as usize],
                    clear: bits >= 48,
                    deposit: if bits % 5 == 0 {
                        Deposit::Boxes
                    } else {
                        Deposit::Cells
                    },
                    region,
                    gather: if bits % 7 == 0 {
                        Gather::Pixels
                    } else if bits % 3 == 0 {
                        Gather::Blocks
                    } else {
                        Gather::Pairs
                    },
                    field: bits & 1 != 0,
                    arrays: bits & 2 != 0,
                    specialize: bits & 4 != 0,
                    needed_rays: bits % 11 < 5,
                    tile: [None, Some(Levers::DEFAULT_TILE_HALO), Some(0), Some(8)]
                        [(bits % 13 % 4) as usize],
                    splat: if bits & 8 != 0 {
                        Splat::Compute
                    } else if bits % 3 == 0 {
                        Splat::Groups
                    } else {
                        Splat::Raster
                    },
                };
                assert_eq!(Levers::parse(&l.to_string()).unwrap(), l);
            }
        }
        let l = Levers::parse("region=full").unwrap();
        assert_eq!(l.region, Region::Full);
        assert!(!l.field && l.arrays && l.specialize && l.splat == Splat::Groups);
        assert_eq!(l.sweep, SweepPath::Auto);
        assert_eq!(
            Levers::parse("sweep=fragment").unwrap().sweep,
            SweepPath::Fragment
        );
        let r = Levers::parse("reference, field=on").unwrap();
        assert_eq!(
            r,
            Levers {
                field: true,
                ..Levers::REFERENCE
            }
        );
        assert_eq!(Levers::parse("default").unwrap(), Levers::default());
    }

    #[test]
    fn bad_variants_say_what_is_wrong() {
        for (spec, needle) in [
            ("", "empty"),
            ("region=polygon", "full, rect or octagon"),
            ("splat=gather", "raster, groups or compute"),
            ("sweep=vertex", "auto, fragment or compute"),
            ("deposit=points", "cells or boxes"),
            ("gather=rays", "pairs, pixels or blocks"),
            ("rays=some", "all or needed"),
            ("tile=9", "a halo in pixels from 0 to 8"),
            ("tile=big", "a halo in pixels from 0 to 8"),
            ("field=maybe", "on or off"),
            ("speed=11", "unknown lever 'speed'"),
            ("field", "not key=value"),
            ("field=on,reference", "can only start"),
        ] {
            let e = Levers::parse(spec).unwrap_err().to_string();
            assert!(e.contains(needle), "{spec}: {e}");
        }
    }

    #[test]
    fn each_flipped_differs_in_exactly_one_lever() {
        let base = Levers::default();
        let flipped = base.each_flipped();
        // Six on/off levers, the region (full, and the octagon's rectangle), and from
        // `auto` both explicit paths.
        assert_eq!(flipped.len(), 10);
        for v in flipped {
            let diffs = [
                v.region != base.region,
                v.field != base.field,
                v.arrays != base.arrays,
                v.specialize != base.specialize,
                v.splat != base.splat,
                v.sweep != base.sweep,
                v.clear != base.clear,
                v.needed_rays != base.needed_rays,
            ];
            assert_eq!(diffs.iter().filter(|d| **d).count(), 1, "{v}");
        }
    }
}
