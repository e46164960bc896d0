//! Skinned, textured avatars on the GPU: the model's vertices, indices, materials and
//! textures are uploaded once ([`AvatarGpu::new`]); each frame only the matrix palettes move.

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::Mat4;
use wgpu::util::DeviceExt;

use crate::skinned::{
    MAX_PALETTE_MATRICES, SkinnedMaterial, SkinnedModel, SkinnedTexture, SkinnedVertex,
};

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct MaterialUniforms {
    base_color: [f32; 4],
    params: [f32; 4],
}

struct PrimitiveGpu {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    material: usize,
    palette: usize,
}

/// The bind group layouts and pipeline of skinned meshes (made once with the renderer).
#[derive(Debug)]
pub(crate) struct SkinnedPipeline {
    pub(crate) pipeline: wgpu::RenderPipeline,
    palette_layout: wgpu::BindGroupLayout,
    material_layout: wgpu::BindGroupLayout,
}

impl SkinnedPipeline {
    pub(crate) fn new(
        device: &wgpu::Device,
        frame_layout: &wgpu::BindGroupLayout,
        shader: &wgpu::ShaderModule,
        depth_stencil: Option<wgpu::DepthStencilState>,
        multisample: wgpu::MultisampleState,
        color_targets: &[Option<wgpu::ColorTargetState>],
    ) -> Self {
        let uniform_entry = |binding, visibility| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let palette_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("stance palette layout"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX)],
        });
        let material_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("stance material layout"),
            entries: &[
                uniform_entry(0, wgpu::ShaderStages::FRAGMENT),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stance skinned layout"),
            bind_group_layouts: &[
                Some(frame_layout),
                Some(&palette_layout),
                Some(&material_layout),
            ],
            immediate_size: 0,
        });
        let vertex_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<SkinnedVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![
                0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Uint32x4, 4 => Float32x4
            ],
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("stance skinned meshes"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(vertex_layout)],
            },
            // Avatars are often double-sided (hair, clothes): no culling.
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil,
            multisample,
            fragment: Some(wgpu::FragmentState {
                module: shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: color_targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        Self {
            pipeline,
            palette_layout,
            material_layout,
        }
    }
}

/// An avatar uploaded to the GPU.
pub struct AvatarGpu {
    primitives: Vec<PrimitiveGpu>,
    /// Per pose drawn in a frame (the first for the selected character, more for others drawn
    /// with the same model), its palettes' buffers and bind groups.
    poses: Vec<Vec<(wgpu::Buffer, wgpu::BindGroup)>>,
    /// How many palettes a pose has.
    palette_count: usize,
    materials: Vec<wgpu::BindGroup>,
    fallback_material: wgpu::BindGroup,
    triangle_count: usize,
}

impl std::fmt::Debug for AvatarGpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AvatarGpu")
            .field("primitives", &self.primitives.len())
            .field("palettes", &self.palette_count)
            .field("poses", &self.poses.len())
            .field("triangles", &self.triangle_count)
            .finish()
    }
}

fn texture_gpu(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &SkinnedTexture,
) -> Option<wgpu::Texture> {
    let gpu = empty_texture_gpu(device, texture)?;
    write_rows(queue, &gpu, texture, 0, texture.height);
    Some(gpu)
}

/// The GPU texture for `texture`, its pixels not written yet; `None` when it is malformed or
/// too large for the device.
fn empty_texture_gpu(device: &wgpu::Device, texture: &SkinnedTexture) -> Option<wgpu::Texture> {
    let expected = (texture.width as usize)
        .checked_mul(texture.height as usize)?
        .checked_mul(4)?;
    if texture.width == 0 || texture.height == 0 || texture.rgba8.len() != expected {
        return None;
    }
    let limit = device.limits().max_texture_dimension_2d;
    if texture.width > limit || texture.height > limit {
        return None;
    }
    Some(device.create_texture(&wgpu::TextureDescriptor {
        label: Some("stance avatar texture"),
        size: wgpu::Extent3d {
            width: texture.width,
            height: texture.height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8UnormSrgb,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    }))
}

/// Writes rows `first..end` of `texture` (already checked by [`empty_texture_gpu`]) into `gpu`.
fn write_rows(
    queue: &wgpu::Queue,
    gpu: &wgpu::Texture,
    texture: &SkinnedTexture,
    first: u32,
    end: u32,
) {
    let row_bytes = texture.width as usize * 4;
    let Some(pixels) = texture
        .rgba8
        .get(first as usize * row_bytes..end as usize * row_bytes)
    else {
        return;
    };
    queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: gpu,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: 0,
                y: first,
                z: 0,
            },
            aspect: wgpu::TextureAspect::All,
        },
        pixels,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(texture.width * 4),
            rows_per_image: Some(end - first),
        },
        wgpu::Extent3d {
            width: texture.width,
            height: end - first,
            depth_or_array_layers: 1,
        },
    );
}

/// A texture's view on the GPU with its wrapping (repeat), or `None` when it is malformed or
/// too large for the device.
fn texture_view(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &SkinnedTexture,
) -> Option<(wgpu::TextureView, bool)> {
    texture_gpu(device, queue, texture).map(|gpu| {
        (
            gpu.create_view(&wgpu::TextureViewDescriptor::default()),
            texture.repeat,
        )
    })
}

/// Pixels written per step of an [`AvatarUpload`] (a 2048-wide texture: 512 rows).
pub const UPLOAD_STEP_BYTES: usize = 4 << 20;

/// An avatar's upload spread over frames: its textures a band of rows per step (about
/// [`UPLOAD_STEP_BYTES`]), then its buffers and bind groups, so that no single frame carries a
/// whole large avatar (three 2048x2048 textures are 48 MB of pixels).
pub struct AvatarUpload {
    model: Arc<SkinnedModel>,
    /// The textures done (`None`: malformed or too large, drawn white).
    textures: Vec<Option<(wgpu::TextureView, bool)>>,
    /// The texture being written and the rows written so far.
    current: Option<(wgpu::Texture, u32)>,
}

impl std::fmt::Debug for AvatarUpload {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AvatarUpload")
            .field("textures_uploaded", &self.textures.len())
            .field("textures", &self.model.textures.len())
            .finish_non_exhaustive()
    }
}

impl AvatarUpload {
    /// An upload of `model` (shared with whoever made it), nothing on the GPU yet.
    pub fn new(model: Arc<SkinnedModel>) -> Self {
        Self {
            textures: Vec::with_capacity(model.textures.len()),
            current: None,
            model,
        }
    }

    /// Writes the next band of rows of the next texture; once every texture is up, uploads
    /// the rest and returns the avatar.
    pub(crate) fn step(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pipeline: &SkinnedPipeline,
    ) -> Option<AvatarGpu> {
        if let Some(texture) = self.model.textures.get(self.textures.len()) {
            let (gpu, done) = match self.current.take() {
                Some(current) => current,
                None => match empty_texture_gpu(device, texture) {
                    Some(gpu) => (gpu, 0),
                    None => {
                        self.textures.push(None);
                        return None;
                    }
                },
            };
            let rows = (UPLOAD_STEP_BYTES / (texture.width as usize * 4)).max(1);
            let end = texture
                .height
                .min(done.saturating_add(u32::try_from(rows).unwrap_or(u32::MAX)));
            write_rows(queue, &gpu, texture, done, end);
            if end < texture.height {
                self.current = Some((gpu, end));
            } else {
                let view = gpu.create_view(&wgpu::TextureViewDescriptor::default());
                self.textures.push(Some((view, texture.repeat)));
            }
            return None;
        }
        let textures = std::mem::take(&mut self.textures);
        Some(AvatarGpu::with_textures(
            device,
            queue,
            pipeline,
            &self.model,
            textures,
        ))
    }
}

/// A 1x1 white texture: what untextured materials sample.
fn white_texture(device: &wgpu::Device, queue: &wgpu::Queue) -> wgpu::Texture {
    let size = wgpu::Extent3d {
        width: 1,
        height: 1,
        depth_or_array_layers: 1,
    };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("stance white texture"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8UnormSrgb,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        &[255; 4],
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(4),
            rows_per_image: Some(1),
        },
        size,
    );
    texture
}

impl AvatarGpu {
    /// Uploads `model`. Textures that are malformed or too large for the device are replaced by
    /// white; palettes are clamped to [`MAX_PALETTE_MATRICES`].
    pub(crate) fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pipeline: &SkinnedPipeline,
        model: &SkinnedModel,
    ) -> Self {
        let textures = model
            .textures
            .iter()
            .map(|texture| texture_view(device, queue, texture))
            .collect();
        Self::with_textures(device, queue, pipeline, model, textures)
    }

    /// Uploads `model` but its textures, given uploaded (`None`: drawn white).
    fn with_textures(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pipeline: &SkinnedPipeline,
        model: &SkinnedModel,
        textures: Vec<Option<(wgpu::TextureView, bool)>>,
    ) -> Self {
        let white = white_texture(device, queue);
        let white_view = white.create_view(&wgpu::TextureViewDescriptor::default());
        let sampler = |repeat: bool| {
            let address_mode = if repeat {
                wgpu::AddressMode::Repeat
            } else {
                wgpu::AddressMode::ClampToEdge
            };
            device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("stance avatar sampler"),
                address_mode_u: address_mode,
                address_mode_v: address_mode,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            })
        };
        let repeat_sampler = sampler(true);
        let clamp_sampler = sampler(false);
        let material_group = |material: &SkinnedMaterial| -> wgpu::BindGroup {
            let (view, repeat) = match material
                .texture
                .and_then(|index| textures.get(index))
                .and_then(Option::as_ref)
            {
                Some((view, repeat)) => (view, *repeat),
                None => (&white_view, true),
            };
            let uniforms = MaterialUniforms {
                base_color: material.base_color_factor,
                params: [
                    if material.unlit { 1.0 } else { 0.0 },
                    material.alpha_cutoff.unwrap_or(0.0),
                    0.0,
                    0.0,
                ],
            };
            let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("stance material"),
                contents: bytemuck::bytes_of(&uniforms),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("stance material bind group"),
                layout: &pipeline.material_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::Sampler(if repeat {
                            &repeat_sampler
                        } else {
                            &clamp_sampler
                        }),
                    },
                ],
            })
        };
        let grey = SkinnedMaterial {
            base_color_factor: [0.6, 0.6, 0.6, 1.0],
            texture: None,
            unlit: false,
            alpha_cutoff: None,
        };
        let materials: Vec<wgpu::BindGroup> = model.materials.iter().map(&material_group).collect();
        let fallback_material = material_group(&grey);
        let palette_count = model.palette_sizes.len();
        let palettes = pose_buffers(device, pipeline, palette_count);
        let mut triangle_count = 0;
        let primitives = model
            .primitives
            .iter()
            .filter(|primitive| !primitive.indices.is_empty() && !primitive.vertices.is_empty())
            .map(|primitive| {
                triangle_count += primitive.indices.len() / 3;
                PrimitiveGpu {
                    vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("stance avatar vertices"),
                        contents: bytemuck::cast_slice(&primitive.vertices),
                        usage: wgpu::BufferUsages::VERTEX,
                    }),
                    indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("stance avatar indices"),
                        contents: bytemuck::cast_slice(&primitive.indices),
                        usage: wgpu::BufferUsages::INDEX,
                    }),
                    index_count: u32::try_from(primitive.indices.len()).unwrap_or(0),
                    material: primitive.material,
                    palette: primitive.palette,
                }
            })
            .collect();
        Self {
            primitives,
            poses: vec![palettes],
            palette_count,
            materials,
            fallback_material,
            triangle_count,
        }
    }

    /// Triangles uploaded.
    pub fn triangle_count(&self) -> usize {
        self.triangle_count
    }

    /// Makes room for `count` poses in a frame (buffers are made once, kept after).
    pub(crate) fn ensure_poses(
        &mut self,
        device: &wgpu::Device,
        pipeline: &SkinnedPipeline,
        count: usize,
    ) {
        while self.poses.len() < count {
            self.poses
                .push(pose_buffers(device, pipeline, self.palette_count));
        }
    }

    /// Writes this frame's palettes of pose `pose` (extra matrices are ignored, missing ones
    /// keep their value).
    pub(crate) fn write_palettes(&self, queue: &wgpu::Queue, pose: usize, palettes: &[Vec<Mat4>]) {
        let Some(buffers) = self.poses.get(pose) else {
            return;
        };
        for ((buffer, _), matrices) in buffers.iter().zip(palettes) {
            let count = matrices.len().min(MAX_PALETTE_MATRICES);
            let Some(matrices) = matrices.get(..count) else {
                continue;
            };
            if matrices.iter().all(|matrix| matrix.is_finite()) && !matrices.is_empty() {
                let columns: Vec<[f32; 16]> = matrices
                    .iter()
                    .map(|matrix| matrix.to_cols_array())
                    .collect();
                queue.write_buffer(buffer, 0, bytemuck::cast_slice(&columns));
            }
        }
    }

    /// Draws every primitive in pose `pose` (the frame bind group is already set at group 0).
    pub(crate) fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        pipeline: &SkinnedPipeline,
        pose: usize,
    ) {
        let Some(buffers) = self.poses.get(pose) else {
            return;
        };
        pass.set_pipeline(&pipeline.pipeline);
        for primitive in &self.primitives {
            let Some((_, palette)) = buffers.get(primitive.palette) else {
                continue;
            };
            let material = self
                .materials
                .get(primitive.material)
                .unwrap_or(&self.fallback_material);
            pass.set_bind_group(1, palette, &[]);
            pass.set_bind_group(2, material, &[]);
            pass.set_vertex_buffer(0, primitive.vertices.slice(..));
            pass.set_index_buffer(primitive.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..primitive.index_count, 0, 0..1);
        }
    }
}

/// One pose's palette buffers (each holds [`MAX_PALETTE_MATRICES`] matrices) and bind groups.
fn pose_buffers(
    device: &wgpu::Device,
    pipeline: &SkinnedPipeline,
    palette_count: usize,
) -> Vec<(wgpu::Buffer, wgpu::BindGroup)> {
    (0..palette_count)
        .map(|_| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("stance palette"),
                size: (MAX_PALETTE_MATRICES * std::mem::size_of::<[f32; 16]>()) as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("stance palette bind group"),
                layout: &pipeline.palette_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                }],
            });
            (buffer, group)
        })
        .collect()
}
