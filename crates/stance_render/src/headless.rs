//! A GPU without a window (native only): `stance render` and the tests draw with it. Any
//! adapter does (lavapipe on CI); `WGPU_BACKEND`, `WGPU_ADAPTER_NAME` and `WGPU_POWER_PREF`
//! choose among them as wgpu documents.

use crate::ImageError;

/// A device, its queue and what the adapter says of itself.
#[derive(Debug)]
pub struct HeadlessGpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter's name and backend.
    pub adapter: wgpu::AdapterInfo,
}

/// Opens the first adapter the environment allows (none asked of a display), with every
/// limit it has: large images need its largest textures.
pub fn headless_gpu() -> Result<HeadlessGpu, ImageError> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(wgpu::util::initialize_adapter_from_env_or_default(
        &instance, None,
    ))
    .map_err(|error| ImageError::NoAdapter(error.to_string()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("stance headless"),
        required_limits: adapter.limits(),
        ..Default::default()
    }))
    .map_err(|error| ImageError::NoAdapter(error.to_string()))?;
    Ok(HeadlessGpu {
        device,
        queue,
        adapter: adapter.get_info(),
    })
}
