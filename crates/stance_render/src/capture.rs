//! Reading a rendered frame back to the CPU: [`Readback`] copies the target and maps the copy
//! without blocking (the browser's GPU answers on a later frame); natively [`read_pixels`]
//! waits for it.

use std::sync::mpsc::{Receiver, TryRecvError};

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

/// Why reading pixels back failed.
#[derive(Debug, thiserror::Error)]
pub enum CaptureError {
    /// Waiting for the GPU to finish the copy failed.
    #[error("the GPU did not finish the copy: {0}")]
    Poll(String),
    /// The read-back buffer could not be mapped for reading.
    #[error("mapping the read-back buffer failed: {0}")]
    Map(String),
}

/// A copy of a target's colour texture on its way to the CPU.
#[derive(Debug)]
pub struct Readback {
    buffer: wgpu::Buffer,
    size_px: [u32; 2],
    padded_row: u32,
    mapped: Receiver<Result<(), wgpu::BufferAsyncError>>,
}

impl Readback {
    /// Copies `target`'s colour texture into a buffer, submits the copy and asks for the
    /// buffer to be mapped; [`Readback::poll`] (or natively [`Readback::wait`]) finishes.
    pub fn start(device: &wgpu::Device, queue: &wgpu::Queue, target: &RenderTarget) -> Self {
        let [width, height] = target.size_px();
        let padded_row = (width * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
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
        let (sender, mapped) = std::sync::mpsc::channel();
        buffer
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |result| {
                let _ = sender.send(result);
            });
        Self {
            buffer,
            size_px: [width, height],
            padded_row,
            mapped,
        }
    }

    /// Width and height of the copied image, pixels.
    pub fn size_px(&self) -> [u32; 2] {
        self.size_px
    }

    /// The pixels once the GPU has mapped the copy; `None` while it has not (call again on a
    /// later frame). Never blocks.
    pub fn poll(&mut self, device: &wgpu::Device) -> Option<Result<Pixels, CaptureError>> {
        if let Err(error) = device.poll(wgpu::PollType::Poll) {
            return Some(Err(CaptureError::Poll(error.to_string())));
        }
        match self.mapped.try_recv() {
            Ok(Ok(())) => Some(self.pixels()),
            Ok(Err(error)) => Some(Err(CaptureError::Map(error.to_string()))),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => Some(Err(CaptureError::Map(
                "the GPU dropped the read-back".to_owned(),
            ))),
        }
    }

    /// Waits for the GPU and returns the pixels (native only: a browser cannot block).
    #[cfg(not(target_arch = "wasm32"))]
    pub fn wait(self, device: &wgpu::Device) -> Result<Pixels, CaptureError> {
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|error| CaptureError::Poll(error.to_string()))?;
        self.mapped
            .recv()
            .map_err(|error| CaptureError::Map(error.to_string()))?
            .map_err(|error| CaptureError::Map(error.to_string()))?;
        self.pixels()
    }

    /// The mapped buffer's rows without their padding.
    fn pixels(&self) -> Result<Pixels, CaptureError> {
        let [width, height] = self.size_px;
        let unpadded_row = (width * 4) as usize;
        let slice = self.buffer.slice(..);
        let mapped = slice
            .get_mapped_range()
            .map_err(|error| CaptureError::Map(error.to_string()))?;
        let mut rgba = Vec::with_capacity(unpadded_row * height as usize);
        for row in mapped
            .chunks(self.padded_row as usize)
            .take(height as usize)
        {
            rgba.extend_from_slice(row.get(..unpadded_row).unwrap_or(row));
        }
        drop(mapped);
        self.buffer.unmap();
        Ok(Pixels {
            width,
            height,
            rgba,
        })
    }
}

/// Copies the target's colour texture to the CPU, waiting for the GPU (native only).
#[cfg(not(target_arch = "wasm32"))]
pub fn read_pixels(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    target: &RenderTarget,
) -> Result<Pixels, CaptureError> {
    Readback::start(device, queue, target).wait(device)
}
