//! Writing frames to disk: 8-bit sRGB PNG or linear float EXR, chosen by the extension.

use std::path::Path;

use anyhow::{bail, Context as _, Result};

use crate::render::Frame;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Exr,
}

/// The output format for a path, or an error naming the path and the accepted extensions.
/// Also checks that the folder exists, so a long render does not fail at the end.
pub fn format_for(path: &Path) -> Result<ImageFormat> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let format = match ext.as_deref() {
        Some("png") => ImageFormat::Png,
        Some("exr") => ImageFormat::Exr,
        Some(other) => bail!(
            "{}: unknown output extension '.{other}'; use .png (8-bit sRGB) or .exr (linear float)",
            path.display()
        ),
        None => bail!(
            "{}: output needs an extension, .png (8-bit sRGB) or .exr (linear float)",
            path.display()
        ),
    };
    if path.is_dir() {
        bail!("{}: is a folder; give a file name", path.display());
    }
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(dir) = parent {
        if !dir.is_dir() {
            bail!(
                "{}: the folder {} does not exist",
                path.display(),
                dir.display()
            );
        }
    }
    Ok(format)
}

/// Linear to sRGB transfer (IEC 61966-2-1), for 8-bit output.
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// 8-bit sRGB RGBA bytes of a frame (alpha stays linear, as PNG expects).
pub fn to_srgb8(frame: &Frame) -> Vec<u8> {
    frame
        .pixels
        .iter()
        .flat_map(|p| {
            [
                (linear_to_srgb(p[0]) * 255.0).round() as u8,
                (linear_to_srgb(p[1]) * 255.0).round() as u8,
                (linear_to_srgb(p[2]) * 255.0).round() as u8,
                (p[3].clamp(0.0, 1.0) * 255.0).round() as u8,
            ]
        })
        .collect()
}

pub fn write(frame: &Frame, path: &Path) -> Result<()> {
    match format_for(path)? {
        ImageFormat::Png => {
            image::save_buffer(
                path,
                &to_srgb8(frame),
                frame.width,
                frame.height,
                image::ExtendedColorType::Rgba8,
            )
            .with_context(|| format!("writing {}", path.display()))?;
        }
        ImageFormat::Exr => write_pixels(frame.width, frame.height, &frame.pixels, path)?,
    }
    Ok(())
}

/// Write raw RGBA f32 pixels (any meaning: colours, directions, positions) as EXR.
pub fn write_pixels(width: u32, height: u32, pixels: &[[f32; 4]], path: &Path) -> Result<()> {
    let w = width as usize;
    exr::prelude::write_rgba_file(path, w, height as usize, |x, y| {
        let p = pixels[y * w + x];
        (p[0], p[1], p[2], p[3])
    })
    .map_err(|e| anyhow::anyhow!("writing {}: {e}", path.display()))
}
