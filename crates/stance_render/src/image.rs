//! One picture of a scene as an image file: rendered offscreen at a chosen size, with or
//! without the overlays and the background, read back and encoded as PNG. `stance render`
//! and the editor's *File > Save image* both go through [`render_image`].

use crate::{CaptureError, OrbitCamera, Pixels, Readback, RenderTarget, Scene, SceneRenderer};

/// The largest side of an image, pixels (the GPU's own limit may be lower).
pub const MAX_IMAGE_SIDE_PX: u32 = 8192;

/// What the image shows and how large it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageOptions {
    /// Width and height, pixels.
    pub size_px: [u32; 2],
    /// Alpha 0 where nothing is drawn (instead of the viewport's background colour).
    pub transparent: bool,
    /// Draw the overlays: the floor grid and the scene's markers (task goals). Without them
    /// the image shows the figure alone (body or avatar).
    pub overlays: bool,
}

impl Default for ImageOptions {
    fn default() -> Self {
        Self {
            size_px: [1280, 960],
            transparent: false,
            overlays: true,
        }
    }
}

impl ImageOptions {
    /// Checks the size against [`MAX_IMAGE_SIDE_PX`] and `device_max_side_px` (the GPU's
    /// largest texture).
    pub fn check(&self, device_max_side_px: u32) -> Result<(), ImageError> {
        let max = MAX_IMAGE_SIDE_PX.min(device_max_side_px);
        let [width, height] = self.size_px;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(ImageError::Size { width, height, max });
        }
        Ok(())
    }

    /// The scene this image draws: `scene` without the floor and markers when the overlays
    /// are off, on a transparent background when asked.
    pub fn scene(&self, scene: &Scene) -> Scene {
        let mut scene = scene.clone();
        if !self.overlays {
            scene.show_floor = false;
            scene.markers.clear();
        }
        scene.transparent_background = self.transparent;
        scene
    }
}

/// Why an image could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// A side is 0 or larger than the limit.
    #[error("image size {width}x{height}: each side must be 1 to {max} pixels")]
    Size {
        /// Asked width.
        width: u32,
        /// Asked height.
        height: u32,
        /// The largest side allowed here.
        max: u32,
    },
    /// No GPU (or software renderer) could be opened.
    #[error(
        "no GPU adapter could be opened ({0}); install a Vulkan or OpenGL driver (Mesa's lavapipe will do)"
    )]
    NoAdapter(String),
    /// Reading the picture back failed.
    #[error(transparent)]
    Capture(#[from] CaptureError),
    /// The PNG encoder failed.
    #[error("PNG encoding failed: {0}")]
    Encode(String),
}

/// An image rendered and on its way back from the GPU.
#[derive(Debug)]
pub struct PendingImage {
    readback: Readback,
    transparent: bool,
}

impl PendingImage {
    /// Width and height of the image, pixels.
    pub fn size_px(&self) -> [u32; 2] {
        self.readback.size_px()
    }

    /// The image (straight alpha) once the GPU is done; `None` before (poll again on a later
    /// frame). Never blocks: the browser's GPU answers between frames.
    pub fn poll(&mut self, device: &wgpu::Device) -> Option<Result<Pixels, ImageError>> {
        let result = self.readback.poll(device)?;
        Some(
            result
                .map(|pixels| straight_alpha(pixels, self.transparent))
                .map_err(ImageError::from),
        )
    }

    /// Waits for the GPU and returns the image (native only).
    #[cfg(not(target_arch = "wasm32"))]
    pub fn wait(self, device: &wgpu::Device) -> Result<Pixels, ImageError> {
        let transparent = self.transparent;
        let pixels = self.readback.wait(device)?;
        Ok(straight_alpha(pixels, transparent))
    }
}

/// Renders `scene` seen by `camera` into a new target of the options' size and starts
/// reading it back. The camera's vertical field of view is kept: a wider image shows more at
/// the sides.
pub fn render_image(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    renderer: &mut SceneRenderer,
    camera: &OrbitCamera,
    scene: &Scene,
    options: &ImageOptions,
) -> Result<PendingImage, ImageError> {
    options.check(device.limits().max_texture_dimension_2d)?;
    let target = RenderTarget::new(device, options.size_px);
    renderer.render(device, queue, &target, camera, &options.scene(scene));
    Ok(PendingImage {
        readback: Readback::start(device, queue, &target),
        transparent: options.transparent,
    })
}

/// The read-back pixels with straight alpha, as PNG stores them. On a transparent
/// background the resolve leaves colours premultiplied by coverage (they were blended with
/// zeros): divided back here. On the opaque background everything is opaque.
fn straight_alpha(mut pixels: Pixels, transparent: bool) -> Pixels {
    for pixel in pixels.rgba.chunks_exact_mut(4) {
        let alpha = pixel[3];
        if !transparent || alpha == 255 {
            pixel[3] = 255;
        } else if alpha == 0 {
            pixel[..3].fill(0);
        } else {
            for channel in &mut pixel[..3] {
                let straight =
                    (u32::from(*channel) * 255 + u32::from(alpha) / 2) / u32::from(alpha);
                *channel = u8::try_from(straight).unwrap_or(u8::MAX);
            }
        }
    }
    pixels
}

/// The pixels as a PNG file (8-bit RGBA, marked sRGB).
pub fn encode_png(pixels: &Pixels) -> Result<Vec<u8>, ImageError> {
    let encode_error = |error: png::EncodingError| ImageError::Encode(error.to_string());
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, pixels.width, pixels.height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let mut writer = encoder.write_header().map_err(encode_error)?;
    writer
        .write_image_data(&pixels.rgba)
        .map_err(encode_error)?;
    writer.finish().map_err(encode_error)?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_of_zero_or_beyond_the_limits_are_refused() {
        let options = |size_px| ImageOptions {
            size_px,
            ..ImageOptions::default()
        };
        assert!(options([320, 200]).check(8192).is_ok());
        assert!(options([0, 200]).check(8192).is_err());
        assert!(options([8193, 10]).check(16384).is_err());
        let error = options([3000, 10]).check(2048).unwrap_err();
        assert!(error.to_string().contains("1 to 2048"), "{error}");
    }

    #[test]
    fn premultiplied_edges_come_back_straight_and_opaque_images_are_opaque() {
        let pixels = Pixels {
            width: 3,
            height: 1,
            rgba: vec![100, 50, 0, 128, 9, 9, 9, 0, 200, 100, 50, 255],
        };
        let straight = straight_alpha(pixels.clone(), true);
        assert_eq!(&straight.rgba[..4], &[199, 100, 0, 128]);
        assert_eq!(&straight.rgba[4..8], &[0, 0, 0, 0]);
        assert_eq!(&straight.rgba[8..], &[200, 100, 50, 255]);
        let opaque = straight_alpha(pixels, false);
        assert!(opaque.rgba.chunks(4).all(|p| p[3] == 255));
    }

    #[test]
    fn the_png_has_the_size_and_pixels_it_was_given() {
        let pixels = Pixels {
            width: 2,
            height: 2,
            rgba: (0..16).map(|i| i * 10).collect(),
        };
        let bytes = encode_png(&pixels).unwrap();
        let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
            .read_info()
            .unwrap();
        let mut out = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut out).unwrap();
        assert_eq!((info.width, info.height), (2, 2));
        assert_eq!(out, pixels.rgba);
    }
}
