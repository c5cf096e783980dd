//! `cogeo devices`: the Vulkan devices and the limits cogeo cares about.

use anyhow::Result;

pub fn run() -> Result<()> {
    let devs = cogeo::gpu::list_devices()?;
    if devs.is_empty() {
        println!("no Vulkan devices found");
    }
    for d in devs {
        println!("{}", d.summary());
    }
    Ok(())
}
