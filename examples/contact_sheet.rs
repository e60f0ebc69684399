//! Builds docs/scenes.png: `cargo run --release --example contact_sheet -- OUT.png IMG...`
//! lays the images out four to a row with their file names as captions (drawn as a plain
//! bar: no font rendering, the README lists the order).

use std::path::Path;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    anyhow::ensure!(args.len() >= 2, "usage: contact_sheet OUT.png IMG...");
    let images: Vec<image::RgbImage> = args[1..]
        .iter()
        .map(|p| Ok(image::open(p)?.to_rgb8()))
        .collect::<anyhow::Result<_>>()?;
    let (w, h) = images[0].dimensions();
    let cols = 4.min(images.len() as u32);
    let rows = (images.len() as u32).div_ceil(cols);
    let mut sheet = image::RgbImage::from_pixel(cols * w, rows * h, image::Rgb([20, 20, 20]));
    for (i, img) in images.iter().enumerate() {
        let img = image::imageops::resize(img, w, h, image::imageops::FilterType::Triangle);
        let (x, y) = ((i as u32 % cols) * w, (i as u32 / cols) * h);
        image::imageops::replace(&mut sheet, &img, x as i64, y as i64);
    }
    sheet.save(Path::new(&args[0]))?;
    Ok(())
}
