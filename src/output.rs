//! Writing frames to disk: 8-bit sRGB PNG or linear float EXR, chosen by the extension.

use std::path::Path;

use anyhow::{bail, Context as _, Result};

use crate::render::Frame;
pub use crate::tone::{linear_to_srgb, ToneMap, ToneOperator};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Exr,
}

/// The output format for a path, or an error naming the path and the accepted extensions.
/// Also checks that the file can be written ([`crate::files::check_writable`]), so a long
/// render does not fail at the end.
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
    crate::files::check_writable(path)?;
    Ok(format)
}

/// The display value in [0, 1] of one linear colour channel: tone mapped, then sRGB
/// encoded; what a PNG stores before rounding to 8 bits.
pub fn display_value(c: f32, tone: &ToneMap) -> f32 {
    linear_to_srgb(tone.apply(c))
}

/// The display values of a frame's RGB channels, as [`to_srgb8`] writes them to a PNG but
/// not rounded to 8 bits (for comparing images finer than 1/255).
pub fn to_display(frame: &Frame, tone: &ToneMap) -> Vec<[f32; 3]> {
    frame
        .pixels
        .iter()
        .map(|p| [0, 1, 2].map(|i| display_value(p[i], tone)))
        .collect()
}

/// 8-bit sRGB RGBA bytes of a frame after tone mapping (alpha stays linear, as PNG
/// expects).
pub fn to_srgb8(frame: &Frame, tone: &ToneMap) -> Vec<u8> {
    let encode = |c: f32| (display_value(c, tone) * 255.0).round() as u8;
    frame
        .pixels
        .iter()
        .flat_map(|p| {
            [
                encode(p[0]),
                encode(p[1]),
                encode(p[2]),
                (p[3].clamp(0.0, 1.0) * 255.0).round() as u8,
            ]
        })
        .collect()
}

/// Write a frame: PNG tone mapped and sRGB encoded, EXR linear HDR. Encoded in memory,
/// then written atomically (crate::files): a failure leaves what was at `path`.
pub fn write(frame: &Frame, path: &Path, tone: &ToneMap) -> Result<()> {
    match format_for(path)? {
        ImageFormat::Png => {
            let bytes = encode_png(&to_srgb8(frame, tone), frame.width, frame.height)
                .with_context(|| format!("{}: cannot encode the PNG", path.display()))?;
            crate::files::write_atomically(path, &bytes)
        }
        ImageFormat::Exr => write_pixels(frame.width, frame.height, &frame.pixels, path),
    }
}

/// 8-bit RGBA bytes as a PNG file's content.
pub fn encode_png(rgba8: &[u8], width: u32, height: u32) -> Result<Vec<u8>> {
    use image::ImageEncoder as _;
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes).write_image(
        rgba8,
        width,
        height,
        image::ExtendedColorType::Rgba8,
    )?;
    Ok(bytes)
}

/// Write raw RGBA f32 pixels (any meaning: colours, directions, positions) as EXR,
/// atomically.
pub fn write_pixels(width: u32, height: u32, pixels: &[[f32; 4]], path: &Path) -> Result<()> {
    write_pixels_with_attributes(width, height, pixels, path, &[])
}

/// A value for an EXR header attribute written by [`write_pixels_with_attributes`].
#[derive(Clone, Debug, PartialEq)]
pub enum HeaderValue {
    /// Latin-1 text (`string` attribute).
    Text(String),
    /// `float` attribute.
    F32(f32),
    /// `int` attribute.
    I32(i32),
    /// `v3f` attribute.
    Vec3([f32; 3]),
}

/// [`write_pixels`] with extra attributes in the header of the file's layer (read back
/// with e.g. `exr::meta::MetaData::read_from_file`: `headers[0].own_attributes.other`).
/// Names and text must be one byte per character (Latin-1).
pub fn write_pixels_with_attributes(
    width: u32,
    height: u32,
    pixels: &[[f32; 4]],
    path: &Path,
    attributes: &[(&str, HeaderValue)],
) -> Result<()> {
    use exr::meta::attribute::{AttributeValue, Text};
    use exr::prelude::*;
    let text = |s: &str| {
        Text::new_or_none(s)
            .with_context(|| format!("EXR header attribute '{s}' has characters beyond Latin-1"))
    };
    let w = width as usize;
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let p = pixels[y * w + x];
        (p[0], p[1], p[2], p[3])
    });
    let mut image = Image::from_channels((w, height as usize), channels);
    for (name, value) in attributes {
        let value = match value {
            HeaderValue::Text(t) => AttributeValue::Text(text(t)?),
            HeaderValue::F32(v) => AttributeValue::F32(*v),
            HeaderValue::I32(v) => AttributeValue::I32(*v),
            HeaderValue::Vec3(v) => AttributeValue::FloatVec3((v[0], v[1], v[2])),
        };
        image.layer_data.attributes.other.insert(text(name)?, value);
    }
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| anyhow::anyhow!("{}: cannot encode the EXR: {e}", path.display()))?;
    crate::files::write_atomically(path, bytes.get_ref())
}
