//! `refrakt info`: the devices and their limits; the validation verdict every GPU
//! command ends with.

use std::process::ExitCode;

use anyhow::Result;

use refrakt::vk::{self, Context, ContextDesc};

pub fn finish(ctx: Context) -> Result<ExitCode> {
    let log = ctx.validation_log();
    drop(ctx);
    let n = log.count();
    if n > 0 {
        eprintln!("validation: {n} message(s) reported (see above)");
        return Ok(ExitCode::from(3));
    }
    Ok(ExitCode::SUCCESS)
}

pub fn info(desc: &ContextDesc) -> Result<ExitCode> {
    let devices = Context::list_devices()?;
    let ctx = Context::new(desc)?;
    println!(
        "Vulkan loader: {}",
        vk::version_string(ctx.loader_version())
    );
    println!("Devices:");
    for d in &devices {
        let mark = if d.index == ctx.info().index {
            "*"
        } else {
            " "
        };
        println!(
            " {mark}[{}] {} ({}), Vulkan {}",
            d.index,
            d.name,
            vk::device_type_name(d.device_type),
            vk::version_string(d.api_version)
        );
    }
    let i = ctx.info();
    let l = &i.limits;
    println!("\nSelected: [{}] {}", i.index, i.name);
    println!(
        "  type:                   {}",
        vk::device_type_name(i.device_type)
    );
    println!(
        "  Vulkan version:         {}",
        vk::version_string(i.api_version)
    );
    println!(
        "  driver:                 {} ({})",
        i.driver_name, i.driver_info
    );
    println!("  max 3D image size:      {}", l.max_image_dimension3_d);
    println!("  max 2D image size:      {}", l.max_image_dimension2_d);
    println!("  max array layers:       {}", l.max_image_array_layers);
    println!(
        "  max push constants:     {} bytes",
        l.max_push_constants_size
    );
    println!("  max colour attachments: {}", l.max_color_attachments);
    println!(
        "  64-bit atomics:         {}",
        if i.int64_atomics {
            "yes (storage buffers)"
        } else {
            "no (sums as two 32-bit words)"
        }
    );
    println!(
        "  timestamps:             {} (period {} ns)",
        if i.timestamps { "yes" } else { "no" },
        l.timestamp_period
    );
    println!("  memory heaps:");
    for (n, (size, device_local)) in i.memory_heaps.iter().enumerate() {
        let local = if *device_local {
            "device-local"
        } else {
            "host"
        };
        println!(
            "    [{n}] {:.1} GiB {local}",
            *size as f64 / (1u64 << 30) as f64
        );
    }
    finish(ctx)
}
