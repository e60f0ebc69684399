//! The logical device: queues, features and extensions enabled on the chosen physical
//! device.

use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;

use super::*;

impl Context {
    pub(super) fn create_device(
        instance: &ash::Instance,
        desc: &ContextDesc,
        surface: Option<(&ash::khr::surface::Instance, vk::SurfaceKHR)>,
    ) -> Result<(vk::PhysicalDevice, DeviceInfo, ash::Device, u32)> {
        // SAFETY: valid instance.
        let physicals = unsafe { instance.enumerate_physical_devices() }?;
        if physicals.is_empty() {
            bail!(
                "no Vulkan device found. On a machine without a GPU install Mesa's lavapipe: \
                 `sudo apt-get install mesa-vulkan-drivers` (scripts/setup.sh does this)"
            );
        }
        let infos: Vec<DeviceInfo> = physicals
            .iter()
            .enumerate()
            .map(|(i, &p)| query_info(instance, p, i))
            .collect();
        // With a window, a device qualifies only if its graphics+compute family can present
        // to the surface and it has VK_KHR_swapchain.
        let presents = |i: usize| -> bool {
            let Some((loader, surface)) = surface else {
                return true;
            };
            queue_family(instance, physicals[i], Some((loader, surface))).is_some()
                && has_device_extension(instance, physicals[i], ash::khr::swapchain::NAME)
        };
        let chosen = match &desc.device {
            Some(sel) => {
                let i = select_device(&infos, sel)?;
                if !presents(i) {
                    bail!(
                        "device '{}' cannot present to this window (no queue with graphics, \
                         compute and presentation, or no VK_KHR_swapchain)",
                        infos[i].name
                    );
                }
                i
            }
            None => infos
                .iter()
                .filter(|i| i.api_version >= vk::API_VERSION_1_3 && presents(i.index))
                .max_by_key(|i| (type_rank(i.device_type), usize::MAX - i.index))
                .map(|i| i.index)
                .ok_or_else(|| {
                    anyhow!(
                        "no Vulkan 1.3 device{} found; devices seen: {}",
                        if surface.is_some() {
                            " that can present to this window"
                        } else {
                            ""
                        },
                        device_list(&infos)
                    )
                })?,
        };
        let info = infos[chosen].clone();
        if info.api_version < vk::API_VERSION_1_3 {
            bail!(
                "device '{}' supports Vulkan {}, refrakt needs 1.3",
                info.name,
                version_string(info.api_version)
            );
        }
        let physical = physicals[chosen];
        // SAFETY: valid physical device.
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let family = queue_family(instance, physical, surface)
            .ok_or_else(|| anyhow!("device '{}' has no graphics+compute queue", info.name))?;
        let mut info = info;
        info.timestamps = info.limits.timestamp_compute_and_graphics == vk::TRUE
            && families[family as usize].timestamp_valid_bits > 0;

        let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut f12)
            .push_next(&mut f13);
        // SAFETY: valid physical device and a well-formed pNext chain.
        unsafe { instance.get_physical_device_features2(physical, &mut f2) };
        let core = f2.features;
        if f13.synchronization2 != vk::TRUE {
            bail!("device '{}' lacks synchronization2", info.name);
        }
        info.large_points = core.large_points == vk::TRUE;
        info.fragment_atomics = core.fragment_stores_and_atomics == vk::TRUE;
        info.multi_draw_indirect = core.multi_draw_indirect == vk::TRUE;
        info.int64_atomics = !desc.without_int64_atomics
            && core.shader_int64 == vk::TRUE
            && f12.shader_buffer_int64_atomics == vk::TRUE;
        let core_features = vk::PhysicalDeviceFeatures::default()
            .large_points(info.large_points)
            .fragment_stores_and_atomics(info.fragment_atomics)
            .multi_draw_indirect(info.multi_draw_indirect)
            .shader_int64(info.int64_atomics);
        let priorities = [1.0f32];
        let queue_infos = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&priorities)];
        // maintenance4 is required by Vulkan 1.3; glslang targeting 1.3 emits LocalSizeId, which
        // needs it enabled.
        let mut enable12 = vk::PhysicalDeviceVulkan12Features::default()
            .shader_buffer_int64_atomics(info.int64_atomics);
        let mut enable13 = vk::PhysicalDeviceVulkan13Features::default()
            .synchronization2(true)
            .maintenance4(true);
        let device_exts: Vec<*const std::ffi::c_char> = if surface.is_some() {
            vec![ash::khr::swapchain::NAME.as_ptr()]
        } else {
            vec![]
        };
        let device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_infos)
            .enabled_extension_names(&device_exts)
            .enabled_features(&core_features)
            .push_next(&mut enable12)
            .push_next(&mut enable13);
        // SAFETY: create info references locals that outlive the call.
        let device = unsafe { instance.create_device(physical, &device_info, None) }
            .with_context(|| format!("creating a logical device on '{}'", info.name))?;
        Ok((physical, info, device, family))
    }
}
