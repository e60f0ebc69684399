//! Choosing the physical device: what each offers (DeviceInfo), ranking, and the user's
//! selection by index or name.

use std::ffi::CStr;

use anyhow::{bail, Result};
use ash::vk;

/// What `refrakt info` prints and what the renderer checks against.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    pub device_type: vk::PhysicalDeviceType,
    pub api_version: u32,
    pub driver_version: u32,
    pub driver_name: String,
    pub driver_info: String,
    pub limits: vk::PhysicalDeviceLimits,
    /// (bytes, device-local) per heap.
    pub memory_heaps: Vec<(u64, bool)>,
    pub timestamps: bool,
    /// Point sizes above 1 (the `largePoints` feature), enabled when offered: the plane
    /// sweep's forward light transport splats each light ray as one point.
    pub large_points: bool,
    /// Storage-buffer atomics in fragment shaders (`fragmentStoresAndAtomics`), enabled
    /// when offered: the plane sweep counts its clamps with them.
    pub fragment_atomics: bool,
    /// Several draws per indirect call (`multiDrawIndirect`), enabled when offered: the
    /// forward transport's grouped point sprites draw each workgroup's leftover rays as one
    /// draw of one call (without it, one call per draw).
    pub multi_draw_indirect: bool,
    /// 64-bit integer atomics on storage buffers (`shaderInt64` and
    /// `shaderBufferInt64Atomics`), enabled when offered: a 64-bit sum is then one atomic
    /// add whose result the shader need not wait for, where two 32-bit words need the low
    /// word's old value for the carry. (Not in shared memory: on an H100 those were slower
    /// than two words, glsl/light_splat_fixed.glsl.)
    pub int64_atomics: bool,
}

pub fn version_string(v: u32) -> String {
    format!(
        "{}.{}.{}",
        vk::api_version_major(v),
        vk::api_version_minor(v),
        vk::api_version_patch(v)
    )
}

pub fn device_type_name(t: vk::PhysicalDeviceType) -> &'static str {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "CPU",
        _ => "other",
    }
}

pub(super) fn type_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 4,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 3,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 1,
        _ => 0,
    }
}

/// The first queue family with graphics and compute (and presentation to `surface`, if
/// given).
pub(super) fn queue_family(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    surface: Option<(&ash::khr::surface::Instance, vk::SurfaceKHR)>,
) -> Option<u32> {
    // SAFETY: valid physical device.
    let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
    families.iter().enumerate().find_map(|(i, f)| {
        let i = i as u32;
        let usable = f
            .queue_flags
            .contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE);
        let presents = match surface {
            // SAFETY: valid physical device, family index and surface of this instance.
            Some((loader, s)) => {
                unsafe { loader.get_physical_device_surface_support(physical, i, s) }
                    .unwrap_or(false)
            }
            None => true,
        };
        (usable && presents).then_some(i)
    })
}

pub(super) fn has_device_extension(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    name: &CStr,
) -> bool {
    // SAFETY: valid physical device.
    unsafe { instance.enumerate_device_extension_properties(physical) }
        .map(|exts| {
            exts.iter()
                .any(|e| e.extension_name_as_c_str().ok() == Some(name))
        })
        .unwrap_or(false)
}

pub(super) fn query_info(
    instance: &ash::Instance,
    p: vk::PhysicalDevice,
    index: usize,
) -> DeviceInfo {
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
    // SAFETY: valid physical device and pNext chain.
    unsafe { instance.get_physical_device_properties2(p, &mut props2) };
    let props = props2.properties;
    let mem = unsafe { instance.get_physical_device_memory_properties(p) };
    let heaps = mem.memory_heaps[..mem.memory_heap_count as usize]
        .iter()
        .map(|h| (h.size, h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL)))
        .collect();
    DeviceInfo {
        index,
        name: props
            .device_name_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        device_type: props.device_type,
        api_version: props.api_version,
        driver_version: props.driver_version,
        driver_name: driver
            .driver_name_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        driver_info: driver
            .driver_info_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        limits: props.limits,
        memory_heaps: heaps,
        timestamps: props.limits.timestamp_compute_and_graphics == vk::TRUE,
        large_points: false,
        fragment_atomics: false,
        multi_draw_indirect: false,
        int64_atomics: false,
    }
}

pub(super) fn device_list(infos: &[DeviceInfo]) -> String {
    infos
        .iter()
        .map(|i| {
            format!(
                "[{}] {} ({})",
                i.index,
                i.name,
                device_type_name(i.device_type)
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// `--device` accepts an index or a case-insensitive substring of the device name.
pub(super) fn select_device(infos: &[DeviceInfo], sel: &str) -> Result<usize> {
    if let Ok(idx) = sel.trim().parse::<usize>() {
        if idx < infos.len() {
            return Ok(idx);
        }
        bail!(
            "--device {sel}: there is no device with index {idx}; devices: {}",
            device_list(infos)
        );
    }
    let needle = sel.trim().to_lowercase();
    if needle.is_empty() {
        bail!(
            "--device '{sel}' is empty: give an index or part of a name; devices: {}",
            device_list(infos)
        );
    }
    let matches: Vec<usize> = infos
        .iter()
        .filter(|i| i.name.to_lowercase().contains(&needle))
        .map(|i| i.index)
        .collect();
    match matches.as_slice() {
        [one] => Ok(*one),
        [] => bail!(
            "--device '{sel}' matches no Vulkan device; devices: {}",
            device_list(infos)
        ),
        many => bail!(
            "--device '{sel}' matches {} devices ({}); give an index instead",
            many.len(),
            device_list(infos)
        ),
    }
}
