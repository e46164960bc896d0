//! Reading a rendered frame back to the CPU (native only): tests and `stance` screenshots.

use crate::RenderTarget;

/// RGBA8 pixels, rows top to bottom, no padding.
#[derive(Debug, Clone, PartialEq)]
pub struct Pixels {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// `width * height * 4` bytes, sRGB-encoded as the target holds them.
    pub rgba: Vec<u8>,
}

impl Pixels {
    /// The pixel at (x, y), or `None` outside the image.
    pub fn get(&self, x: u32, y: u32) -> Option<[u8; 4]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let start = ((y * self.width + x) * 4) as usize;
        let bytes = self.rgba.get(start..start + 4)?;
        Some([bytes[0], bytes[1], bytes[2], bytes[3]])
    }
}

/// Why [`read_pixels`] failed.
#[derive(Debug, thiserror::Error)]
pub enum CaptureError {
    /// Waiting for the GPU to finish the copy failed.
    #[error("the GPU did not finish the copy: {0}")]
    Poll(String),
    /// The read-back buffer could not be mapped for reading.
    #[error("mapping the read-back buffer failed: {0}")]
    Map(String),
}

/// Copies the target's colour texture to the CPU, waiting for the GPU.
pub fn read_pixels(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    target: &RenderTarget,
) -> Result<Pixels, CaptureError> {
    let [width, height] = target.size_px();
    let unpadded_row = width * 4;
    let padded_row = unpadded_row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
        * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("stance read-back"),
        size: u64::from(padded_row) * u64::from(height),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("stance read-back"),
    });
    encoder.copy_texture_to_buffer(
        target.color_texture().as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);
    let slice = buffer.slice(..);
    let (sender, receiver) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |result| {
        let _ = sender.send(result);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|error| CaptureError::Poll(error.to_string()))?;
    receiver
        .recv()
        .map_err(|error| CaptureError::Map(error.to_string()))?
        .map_err(|error| CaptureError::Map(error.to_string()))?;
    let mapped = slice
        .get_mapped_range()
        .map_err(|error| CaptureError::Map(error.to_string()))?;
    let mut rgba = Vec::with_capacity((unpadded_row * height) as usize);
    for row in mapped.chunks(padded_row as usize).take(height as usize) {
        rgba.extend_from_slice(row.get(..unpadded_row as usize).unwrap_or(row));
    }
    drop(mapped);
    buffer.unmap();
    Ok(Pixels {
        width,
        height,
        rgba,
    })
}
