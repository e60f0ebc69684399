//! The Vulkan instance: loading the loader, instance extensions and layers, and the
//! validation messenger's callback.

use std::ffi::{c_void, CStr};

use anyhow::{anyhow, Context as _, Result};
use ash::vk;

use super::*;

pub(super) const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

pub(super) unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: the layer passes a valid callback-data pointer; `user` points into the
    // `Arc<ValidationLog>` that `Shared` owns until after the messenger is destroyed.
    let (msg, log) = unsafe {
        let data = &*data;
        let msg = if data.p_message.is_null() {
            String::from("(no message)")
        } else {
            CStr::from_ptr(data.p_message)
                .to_string_lossy()
                .into_owned()
        };
        (msg, &*(user as *const ValidationLog))
    };
    let counted = severity.intersects(
        vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
            | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
    );
    if counted {
        log::error!("[vulkan {types:?} {severity:?}] {msg}");
        log.messages.lock().unwrap().push(msg);
    } else {
        log::debug!("[vulkan {types:?} {severity:?}] {msg}");
    }
    vk::FALSE
}

pub(super) fn load_entry() -> Result<ash::Entry> {
    // SAFETY: loading the system Vulkan loader library; nothing else runs concurrently with
    // its initialisation in this process that could observe a half-loaded library.
    unsafe { ash::Entry::load() }.map_err(|e| {
        anyhow!(
            "cannot load the Vulkan loader (libvulkan.so.1): {e}. Install it with \
             `sudo apt-get install libvulkan1 mesa-vulkan-drivers` or run scripts/setup.sh"
        )
    })
}

pub(super) fn create_instance(
    entry: &ash::Entry,
    validate: bool,
    debug_utils: bool,
    extra_extensions: &[*const std::ffi::c_char],
) -> Result<ash::Instance> {
    let app = vk::ApplicationInfo::default()
        .application_name(c"refrakt")
        .engine_name(c"refrakt")
        .api_version(vk::API_VERSION_1_3);
    let layers: Vec<*const i8> = if validate {
        vec![VALIDATION_LAYER.as_ptr()]
    } else {
        vec![]
    };
    let mut exts: Vec<*const i8> = vec![];
    if debug_utils {
        exts.push(ash::ext::debug_utils::NAME.as_ptr());
    }
    exts.extend_from_slice(extra_extensions);
    // Synchronization validation is off by default in the layer; it is the check that
    // vouches for our barriers (plane sweep, compute passes), so it is always on with
    // --validate.
    let enabled = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&exts);
    if validate {
        info = info.push_next(&mut features);
    }
    // SAFETY: create info references locals that outlive the call.
    unsafe { entry.create_instance(&info, None) }.context("creating the Vulkan instance")
}
