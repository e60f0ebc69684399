//! Instance, physical-device choice, logical device, allocator and the validation messenger.
//!
//! Headless by default: no surface extension is requested, so the same code runs on a machine
//! with no window system (CI on lavapipe). With [`ContextDesc::window`] the instance gets the
//! window system's surface extensions, the surface is made with the instance, only devices
//! that can present to it are considered, and the device enables VK_KHR_swapchain (the
//! swapchain itself is `super::swapchain`). A [`Context`] is a cheap handle (an `Arc`); every
//! resource keeps one, so the device outlives whatever was made from it.

use std::ffi::{c_void, CStr, CString};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};

mod device;
mod instance;
mod selection;

use instance::*;
use selection::*;
pub use selection::{device_type_name, version_string, DeviceInfo};

/// A window the context presents to: anything with raw display and window handles (a
/// winit `Window`). The context keeps it alive until its surface is destroyed.
pub trait WindowSource: HasDisplayHandle + HasWindowHandle + Send + Sync {}
impl<T: HasDisplayHandle + HasWindowHandle + Send + Sync> WindowSource for T {}

/// How to build a [`Context`].
#[derive(Clone, Default)]
pub struct ContextDesc {
    /// Turn on VK_LAYER_KHRONOS_validation with synchronization validation.
    pub validate: bool,
    /// Device name (case-insensitive substring) or index into the enumeration order.
    pub device: Option<String>,
    /// Present to this window: enables the surface instance extensions it needs
    /// (ash-window) and VK_KHR_swapchain, creates its surface, and chooses only among
    /// devices whose graphics+compute queue can present to it. None = headless.
    pub window: Option<Arc<dyn WindowSource>>,
    /// Leave 64-bit atomics off even where the device offers them
    /// ([`DeviceInfo::int64_atomics`] false), so that tests run the two-word
    /// paths the devices without them take.
    pub without_int64_atomics: bool,
}

impl std::fmt::Debug for ContextDesc {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ContextDesc")
            .field("validate", &self.validate)
            .field("device", &self.device)
            .field("window", &self.window.is_some())
            .field("without_int64_atomics", &self.without_int64_atomics)
            .finish()
    }
}

impl ContextDesc {
    /// Validation on when `validate` is set or `REFRAKT_VALIDATE` is `1`/`true` (`0`/
    /// `false`/empty: off). Anything else is an error: a typo must not silently turn
    /// validation off.
    pub fn from_env(validate: bool, device: Option<String>) -> Result<Self> {
        let env = match std::env::var("REFRAKT_VALIDATE") {
            Err(std::env::VarError::NotPresent) => false,
            Err(std::env::VarError::NotUnicode(v)) => {
                bail!("REFRAKT_VALIDATE={v:?}: use 1 or true (on), 0 or false (off)")
            }
            Ok(v) => parse_switch(&v).ok_or_else(|| {
                anyhow!(
                    "REFRAKT_VALIDATE={:?}: use 1 or true (on), 0 or false (off)",
                    v.chars().take(40).collect::<String>()
                )
            })?,
        };
        Ok(Self {
            validate: validate || env,
            device,
            window: None,
            without_int64_atomics: false,
        })
    }
}

/// Messages the validation layer reported (warnings and errors only).
#[derive(Default)]
pub struct ValidationLog {
    messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().unwrap().clone()
    }
    pub fn count(&self) -> usize {
        self.messages.lock().unwrap().len()
    }
}

/// The window surface of a presenting context, destroyed before the instance.
pub(crate) struct SurfaceState {
    pub(crate) loader: ash::khr::surface::Instance,
    pub(crate) raw: vk::SurfaceKHR,
    pub(crate) swapchain_loader: ash::khr::swapchain::Device,
    // Keeps the window alive as long as the surface exists.
    _window: Arc<dyn WindowSource>,
}

pub(crate) struct Shared {
    _entry: ash::Entry,
    pub(crate) instance: ash::Instance,
    debug_instance: Option<ash::ext::debug_utils::Instance>,
    messenger: vk::DebugUtilsMessengerEXT,
    pub(crate) debug_device: Option<ash::ext::debug_utils::Device>,
    pub(crate) physical: vk::PhysicalDevice,
    pub(crate) device: ash::Device,
    pub(crate) queue: Mutex<vk::Queue>,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
    pub(crate) command_pool: Mutex<vk::CommandPool>,
    // Also the messenger's user data: it outlives the messenger because Shared destroys
    // the messenger in Drop before its fields drop.
    validation: Arc<ValidationLog>,
    pub(crate) info: DeviceInfo,
    loader_version: u32,
    pub(crate) queue_family: u32,
    pub(crate) surface: Option<SurfaceState>,
}

/// A Vulkan 1.3 device with one graphics+compute queue.
#[derive(Clone)]
pub struct Context {
    pub(crate) shared: Arc<Shared>,
}

impl Context {
    /// List the devices the loader sees, in enumeration order.
    pub fn list_devices() -> Result<Vec<DeviceInfo>> {
        let entry = load_entry()?;
        let instance = create_instance(&entry, false, false, &[])?;
        let result = (|| {
            // SAFETY: valid instance.
            let physicals = unsafe { instance.enumerate_physical_devices() }?;
            Ok(physicals
                .iter()
                .enumerate()
                .map(|(i, &p)| query_info(&instance, p, i))
                .collect())
        })();
        // SAFETY: nothing made from this instance survives.
        unsafe { instance.destroy_instance(None) };
        result
    }

    pub fn new(desc: &ContextDesc) -> Result<Self> {
        let entry = load_entry()?;
        // SAFETY: plain enumeration calls on a loaded entry.
        let layers = unsafe { entry.enumerate_instance_layer_properties() }?;
        let have_validation = layers
            .iter()
            .any(|l| l.layer_name_as_c_str().ok() == Some(VALIDATION_LAYER));
        if desc.validate && !have_validation {
            bail!(
                "validation was requested but VK_LAYER_KHRONOS_validation is not installed \
                 (Debian package vulkan-validationlayers; scripts/setup.sh installs it)"
            );
        }
        let exts = unsafe { entry.enumerate_instance_extension_properties(None) }?;
        let have_debug_utils = exts
            .iter()
            .any(|e| e.extension_name_as_c_str().ok() == Some(ash::ext::debug_utils::NAME));
        // SAFETY: plain query.
        let loader_version =
            unsafe { entry.try_enumerate_instance_version() }?.unwrap_or(vk::API_VERSION_1_0);
        if loader_version < vk::API_VERSION_1_3 {
            bail!(
                "the Vulkan loader supports only {}, refrakt needs 1.3",
                version_string(loader_version)
            );
        }

        let window_exts: &[*const std::ffi::c_char] = match &desc.window {
            Some(w) => {
                let display = w
                    .display_handle()
                    .map_err(|e| anyhow!("the window has no display handle: {e}"))?;
                ash_window::enumerate_required_extensions(display.as_raw()).context(
                    "this window system has no Vulkan surface extension (X11 and Wayland do)",
                )?
            }
            None => &[],
        };
        for &ext in window_exts {
            // SAFETY: ash-window returns pointers to static NUL-terminated names.
            let name = unsafe { CStr::from_ptr(ext) };
            if !exts
                .iter()
                .any(|e| e.extension_name_as_c_str().ok() == Some(name))
            {
                bail!(
                    "the Vulkan loader lacks the instance extension {} needed to show a window",
                    name.to_string_lossy()
                );
            }
        }
        let instance = create_instance(&entry, desc.validate, have_debug_utils, window_exts)?;
        let validation = Arc::new(ValidationLog::default());
        let (debug_instance, messenger) = if have_debug_utils {
            let di = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                        | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                        | vk::DebugUtilsMessageSeverityFlagsEXT::INFO,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(debug_callback))
                .user_data(Arc::as_ptr(&validation) as *mut c_void);
            // SAFETY: `validation` is kept alive in `Shared` until the messenger is destroyed.
            let m = unsafe { di.create_debug_utils_messenger(&info, None) }?;
            (Some(di), m)
        } else {
            (None, vk::DebugUtilsMessengerEXT::null())
        };

        let surface_loader = ash::khr::surface::Instance::new(&entry, &instance);
        let surface = match &desc.window {
            // SAFETY: the handles come from a live window that the context keeps alive (in
            // SurfaceState) until the surface is destroyed; the instance has the extensions
            // ash-window asked for.
            Some(w) => match (w.display_handle(), w.window_handle()) {
                (Ok(d), Ok(h)) => unsafe {
                    ash_window::create_surface(&entry, &instance, d.as_raw(), h.as_raw(), None)
                }
                .context("creating the window's Vulkan surface"),
                (Err(e), _) | (_, Err(e)) => Err(anyhow!("the window has no handle: {e}")),
            }
            .map(Some),
            None => Ok(None),
        };
        let built = surface.and_then(|surface| {
            let target = surface.map(|s| (&surface_loader, s));
            Self::create_device(&instance, desc, target)
                .map(|d| (d, surface))
                .inspect_err(|_| {
                    if let Some(s) = surface {
                        // SAFETY: nothing else uses the surface yet.
                        unsafe { surface_loader.destroy_surface(s, None) };
                    }
                })
        });
        let ((physical, info, device, queue_family), surface) = match built {
            Ok(v) => v,
            Err(e) => {
                // SAFETY: nothing else was created from the instance.
                unsafe {
                    if let Some(di) = &debug_instance {
                        di.destroy_debug_utils_messenger(messenger, None);
                    }
                    instance.destroy_instance(None);
                }
                return Err(e);
            }
        };
        let surface = match (surface, &desc.window) {
            (Some(raw), Some(window)) => Some(SurfaceState {
                loader: surface_loader,
                raw,
                swapchain_loader: ash::khr::swapchain::Device::new(&instance, &device),
                _window: window.clone(),
            }),
            _ => None,
        };
        // SAFETY: family index was chosen from this device's queue families.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .context("creating the GPU memory allocator")?;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid device.
        let command_pool = unsafe { device.create_command_pool(&pool_info, None) }?;
        let debug_device =
            have_debug_utils.then(|| ash::ext::debug_utils::Device::new(&instance, &device));

        Ok(Self {
            shared: Arc::new(Shared {
                _entry: entry,
                instance,
                debug_instance,
                messenger,
                debug_device,
                physical,
                device,
                queue: Mutex::new(queue),
                allocator: ManuallyDrop::new(Mutex::new(allocator)),
                command_pool: Mutex::new(command_pool),
                validation,
                info,
                loader_version,
                queue_family,
                surface,
            }),
        })
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.shared.info
    }

    pub fn loader_version(&self) -> u32 {
        self.shared.loader_version
    }

    /// The validation messages (warnings and errors) reported so far. Kept alive by the
    /// returned `Arc` even after the context is dropped, so a test can check destruction too.
    pub fn validation_log(&self) -> Arc<ValidationLog> {
        self.shared.validation.clone()
    }

    pub fn device(&self) -> &ash::Device {
        &self.shared.device
    }

    /// Whether a format supports the given features for optimal-tiling images.
    pub fn format_supports(&self, format: vk::Format, features: vk::FormatFeatureFlags) -> bool {
        // SAFETY: valid physical device.
        let props = unsafe {
            self.shared
                .instance
                .get_physical_device_format_properties(self.shared.physical, format)
        };
        props.optimal_tiling_features.contains(features)
    }

    /// Wait until the device is idle (used before teardown and in tests).
    pub fn wait_idle(&self) -> Result<()> {
        // SAFETY: valid device; the queue lock keeps other submits out meanwhile.
        let _q = self.shared.queue.lock().unwrap();
        unsafe { self.shared.device.device_wait_idle() }?;
        Ok(())
    }

    /// Attach a debug name to a Vulkan object (shows up in RenderDoc, Nsight and in
    /// validation messages).
    pub(crate) fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(dd) = &self.shared.debug_device {
            let Ok(cname) = CString::new(name) else {
                return;
            };
            let info = vk::DebugUtilsObjectNameInfoEXT::default()
                .object_handle(handle)
                .object_name(&cname);
            // SAFETY: handle belongs to this device.
            let _ = unsafe { dd.set_debug_utils_object_name(&info) };
        }
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        // SAFETY: every resource holds a Context, so when Shared drops nothing made from the
        // device is alive any more. Order: idle, allocator, pool, device, messenger, instance.
        unsafe {
            let _ = self.device.device_wait_idle();
            ManuallyDrop::drop(&mut self.allocator);
            self.device
                .destroy_command_pool(*self.command_pool.get_mut().unwrap(), None);
            self.device.destroy_device(None);
            // Every swapchain holds a Context, so none is left on the surface.
            if let Some(s) = &self.surface {
                s.loader.destroy_surface(s.raw, None);
            }
            if let Some(di) = &self.debug_instance {
                di.destroy_debug_utils_messenger(self.messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// `1`/`true` → on, `0`/`false`/empty → off (case-insensitive, trimmed), else `None`.
fn parse_switch(v: &str) -> Option<bool> {
    match v.trim().to_ascii_lowercase().as_str() {
        "1" | "true" => Some(true),
        "0" | "false" | "" => Some(false),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::parse_switch;

    #[test]
    fn validation_switch_accepts_only_on_and_off() {
        assert_eq!(parse_switch("1"), Some(true));
        assert_eq!(parse_switch(" TRUE "), Some(true));
        assert_eq!(parse_switch("0"), Some(false));
        assert_eq!(parse_switch("false"), Some(false));
        assert_eq!(parse_switch(""), Some(false));
        assert_eq!(parse_switch("banana"), None);
        assert_eq!(parse_switch("yes"), None);
    }
}
