//! Submitting a recording and waiting for it; uploads and read-backs of images.

use anyhow::{bail, Context as _, Result};
use ash::vk;

use crate::vk::{Access, Buffer, Context, Image, Memory};

use super::*;

/// How often [`Context::execute_observed`] looks at the progress marks.
const PROGRESS_POLL_NS: u64 = 200_000_000;

impl Context {
    /// Record a command buffer with `record`, submit it, wait for it, and return the GPU
    /// time of each scope the recording opened.
    pub fn execute(&self, record: impl FnOnce(&mut Recorder) -> Result<()>) -> Result<Timings> {
        self.submit_and_wait(record, None)
    }

    /// [`Context::execute`], reporting progress while the GPU runs: `observe` is called
    /// every 0.2 s with the fraction of the marked work done (the
    /// recording's [`Recorder::progress`] marks; 0 until the first is passed), and once
    /// with 1 when the submission completes. The frame stays one command buffer: the host
    /// reads the marks' timestamps as they become available. Without timestamp queries
    /// there are no marks and `observe` sees 0, then 1.
    pub fn execute_observed(
        &self,
        record: impl FnOnce(&mut Recorder) -> Result<()>,
        observe: &mut dyn FnMut(f64),
    ) -> Result<Timings> {
        self.submit_and_wait(record, Some(observe))
    }

    fn submit_and_wait(
        &self,
        record: impl FnOnce(&mut Recorder) -> Result<()>,
        mut observe: Option<&mut dyn FnMut(f64)>,
    ) -> Result<Timings> {
        let device = self.device();
        let pool = *self.shared.command_pool.lock().unwrap();
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // The pool is shared by all threads using this context; allocation and freeing hold
        // its lock, recording happens on a buffer nobody else sees.
        let cmd = {
            let _guard = self.shared.command_pool.lock().unwrap();
            // SAFETY: the pool lock is held.
            unsafe { device.allocate_command_buffers(&alloc) }?[0]
        };
        let queries = match create_query_pool(self) {
            Ok(q) => q,
            Err(e) => {
                let _guard = self.shared.command_pool.lock().unwrap();
                // SAFETY: never submitted.
                unsafe { device.free_command_buffers(pool, &[cmd]) };
                return Err(e);
            }
        };
        let result = (|| -> Result<Timings> {
            // The progress marks' words, zeroed (see Recorder::progress).
            let marks = match observe {
                Some(_) => {
                    let mut b = Buffer::new(
                        self,
                        4 * MAX_MARKS,
                        vk::BufferUsageFlags::TRANSFER_DST,
                        Memory::Upload,
                        "progress marks",
                    )?;
                    b.write(0, &[0u8; 4 * MAX_MARKS as usize])?;
                    Some(b)
                }
                None => None,
            };
            let mut rec = Recorder::begin(self, cmd, queries, marks.as_ref().map(|b| b.raw))?;
            record(&mut rec)?;
            let pending = rec.finish()?;
            // SAFETY: recording finished; fence waited before anything is read or freed.
            unsafe {
                let fence = device.create_fence(&vk::FenceCreateInfo::default(), None)?;
                let cmd_infos = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
                let submit = vk::SubmitInfo2::default().command_buffer_infos(&cmd_infos);
                let submitted = {
                    let queue = self.shared.queue.lock().unwrap();
                    device.queue_submit2(*queue, &[submit], fence)
                };
                let waited = submitted.and_then(|_| match observe.as_mut() {
                    None => device.wait_for_fences(&[fence], true, u64::MAX),
                    Some(observe) => {
                        let mut next = 0;
                        observe(0.0);
                        loop {
                            match device.wait_for_fences(&[fence], true, PROGRESS_POLL_NS) {
                                Err(vk::Result::TIMEOUT) => {
                                    let words = marks.as_ref().and_then(|b| b.mapped().ok());
                                    let passed = |k: usize| {
                                        words.is_some_and(|w| {
                                            // Written by the GPU while we read: a
                                            // volatile read of the whole word (0 or 1).
                                            let p = w[4 * k..4 * k + 4].as_ptr() as *const u32;
                                            std::ptr::read_volatile(p) != 0
                                        })
                                    };
                                    let before = next;
                                    while next < pending.marks.len() && passed(next) {
                                        next += 1;
                                    }
                                    if next > before {
                                        observe(pending.marks[next - 1]);
                                    }
                                }
                                Ok(()) => {
                                    observe(1.0);
                                    break Ok(());
                                }
                                Err(e) => break Err(e),
                            }
                        }
                    }
                });
                device.destroy_fence(fence, None);
                waited.context("GPU submission failed (device lost?)")?;
            }
            pending.resolve(self, queries)
        })();
        // SAFETY: the submission (if any) has completed or failed; nothing references these.
        unsafe {
            if let Some(q) = queries {
                device.destroy_query_pool(q, None);
            }
            let _guard = self.shared.command_pool.lock().unwrap();
            device.free_command_buffers(pool, &[cmd]);
        }
        result
    }

    /// Upload tightly packed texels into one layer of `image`; the layer ends up ready for
    /// sampling.
    pub fn upload_image(&self, image: &Image, layer: u32, bytes: &[u8]) -> Result<()> {
        let expected = image.layer_bytes()?;
        if bytes.len() as u64 != expected {
            bail!(
                "upload to '{}' has {} bytes, one layer is {expected}",
                image.name(),
                bytes.len()
            );
        }
        let mut staging = Buffer::new(
            self,
            expected,
            vk::BufferUsageFlags::TRANSFER_SRC,
            Memory::Upload,
            "staging upload",
        )?;
        staging.write(0, bytes)?;
        self.execute(|rec| {
            rec.copy_buffer_to_image(&staging, image, layer);
            rec.transition(image, layer..layer + 1, Access::Sampled);
            Ok(())
        })?;
        Ok(())
    }

    /// Read one layer of `image` back to the host as tightly packed texels.
    pub fn read_image(&self, image: &Image, layer: u32) -> Result<Vec<u8>> {
        let size = image.layer_bytes()?;
        let staging = Buffer::new(
            self,
            size,
            vk::BufferUsageFlags::TRANSFER_DST,
            Memory::Readback,
            "staging readback",
        )?;
        self.execute(|rec| {
            rec.copy_image_to_buffer(image, layer, &staging);
            Ok(())
        })?;
        Ok(staging.mapped()?[..size as usize].to_vec())
    }
}
