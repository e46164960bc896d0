//! GPU resources and the draw of one frame.

use bytemuck::{Pod, Zeroable};
use glam::Vec2;
use wgpu::util::DeviceExt;

use crate::props::{MeshPropInstance, PropInstance, PropTemplate, normal_matrix, prop_mesh};
use crate::skinned::SkinnedModel;
use crate::skinned_gpu::{AvatarGpu, AvatarUpload, SkinnedPipeline};
use crate::{MAX_CONTACT_SHADOWS, OrbitCamera, SHADERS, Scene};

mod cast;
use cast::CastModel;

/// Colour format of the render target: what egui can show as a native texture. The shaders
/// write sRGB-encoded values into it.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Depth format of the render target.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth24Plus;
const SAMPLE_COUNT: u32 = 4;
/// Direction the key light travels (from above, front-left).
const LIGHT_DIRECTION_WORLD: [f32; 4] = [-0.4, -0.8, -0.45, 0.0];

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct FrameUniforms {
    clip_from_world: [[f32; 4]; 4],
    camera_position_world: [f32; 4],
    light_direction_world: [f32; 4],
    background: [f32; 4],
    view_from_world: [[f32; 4]; 4],
    /// x: 0 shaded, 1 depth, 2 normals, 3 mask; y, z: the depth range (m).
    control_map: [f32; 4],
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct CapsuleInstance {
    start_and_radius: [f32; 4],
    end_world: [f32; 4],
    color: [f32; 4],
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct PropVertex {
    position: [f32; 4],
    normal: [f32; 4],
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct PropGpuInstance {
    world_from_unit: [[f32; 4]; 4],
    normals: [[f32; 4]; 3],
    color: [f32; 4],
}

/// A mesh prop's triangles on the GPU: its parts' points in one vertex buffer and their
/// triangles in one index buffer, each part's indices pointing into the whole vertex buffer
/// (drawn from base vertex 0, as WebGL2 needs: see [`PropPipeline::ranges`]).
#[derive(Debug)]
struct GpuPropMesh {
    /// The mesh it was made from (kept: the cache is keyed by this pointer).
    source: std::sync::Arc<stance_asset::PropMesh>,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    /// Per part: its index range.
    parts: Vec<std::ops::Range<u32>>,
}

impl GpuPropMesh {
    fn new(device: &wgpu::Device, mesh: &std::sync::Arc<stance_asset::PropMesh>) -> Self {
        let mut vertices = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut parts = Vec::with_capacity(mesh.parts.len());
        for part in &mesh.parts {
            let first_vertex = u32::try_from(vertices.len()).unwrap_or(0);
            let first_index = u32::try_from(indices.len()).unwrap_or(0);
            vertices.extend(
                part.positions
                    .iter()
                    .zip(&part.normals)
                    .map(|(p, n)| PropVertex {
                        position: [p[0], p[1], p[2], 1.0],
                        normal: [n[0], n[1], n[2], 0.0],
                    }),
            );
            indices.extend(part.indices.iter().map(|&i| first_vertex + i));
            parts.push(first_index..u32::try_from(indices.len()).unwrap_or(0));
        }
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("stance mesh prop vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("stance mesh prop indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        Self {
            source: mesh.clone(),
            vertices,
            indices,
            parts,
        }
    }
}

/// What a frame draws of the props: each template's instance range, and each mesh prop
/// part's (its GPU mesh, its index range, its instance).
#[derive(Debug, Default)]
struct PropDraws {
    groups: Vec<std::ops::Range<u32>>,
    meshes: Vec<(usize, std::ops::Range<u32>, u32)>,
}

/// The props' pipeline, the unit shapes' combined mesh, the mesh props' meshes and the
/// instances' buffer.
#[derive(Debug)]
struct PropPipeline {
    pipeline: wgpu::RenderPipeline,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    /// Per template (in [`PropTemplate::ALL`]'s order): its index range. The indices point
    /// into the whole vertex buffer: WebGL2 draws no instances from a base vertex other than
    /// 0 (glow panics: "Draw elements instanced base vertex is not supported").
    ranges: Vec<std::ops::Range<u32>>,
    instances: wgpu::Buffer,
    capacity: usize,
    /// The mesh props' triangles drawn last frame (dropped when no prop draws them).
    meshes: Vec<GpuPropMesh>,
}

impl PropPipeline {
    fn new(
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        shader: &wgpu::ShaderModule,
        depth_stencil: Option<wgpu::DepthStencilState>,
        multisample: wgpu::MultisampleState,
        color_targets: &[Option<wgpu::ColorTargetState>],
    ) -> Self {
        let vertex_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<PropVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4],
        };
        let instance_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<PropGpuInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &wgpu::vertex_attr_array![
                2 => Float32x4, 3 => Float32x4, 4 => Float32x4, 5 => Float32x4,
                6 => Float32x4, 7 => Float32x4, 8 => Float32x4, 9 => Float32x4
            ],
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("stance props"),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module: shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(vertex_layout), Some(instance_layout)],
            },
            primitive: wgpu::PrimitiveState {
                cull_mode: Some(wgpu::Face::Back),
                front_face: wgpu::FrontFace::Ccw,
                ..Default::default()
            },
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
        let mut vertices = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut ranges = Vec::new();
        for template in PropTemplate::ALL {
            let mesh = prop_mesh(template);
            let first_vertex = u32::try_from(vertices.len()).unwrap_or(0);
            let first_index = u32::try_from(indices.len()).unwrap_or(0);
            vertices.extend(
                mesh.positions
                    .iter()
                    .zip(&mesh.normals)
                    .map(|(p, n)| PropVertex {
                        position: p.extend(1.0).to_array(),
                        normal: n.extend(0.0).to_array(),
                    }),
            );
            indices.extend(mesh.indices.iter().map(|&i| first_vertex + u32::from(i)));
            let end = u32::try_from(indices.len()).unwrap_or(0);
            ranges.push(first_index..end);
        }
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("stance prop vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("stance prop indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let capacity = 16;
        Self {
            pipeline,
            vertices,
            indices,
            ranges,
            instances: Self::instance_buffer(device, capacity),
            capacity,
            meshes: Vec::new(),
        }
    }

    fn instance_buffer(device: &wgpu::Device, capacity: usize) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stance prop instances"),
            size: (capacity * std::mem::size_of::<PropGpuInstance>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Writes `props`' instances, grouped by template, then one per part of each of
    /// `mesh_props` (their meshes put on the GPU when new); returns what to draw.
    fn write(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        props: &[PropInstance],
        mesh_props: &[MeshPropInstance],
    ) -> PropDraws {
        let mut instances = Vec::with_capacity(props.len());
        let mut groups = Vec::with_capacity(PropTemplate::ALL.len());
        for template in PropTemplate::ALL {
            let start = u32::try_from(instances.len()).unwrap_or(u32::MAX);
            instances.extend(
                props
                    .iter()
                    .filter(|prop| prop.template == template && prop.world_from_unit.is_finite())
                    .map(|prop| {
                        let normals = normal_matrix(prop.world_from_unit);
                        PropGpuInstance {
                            world_from_unit: prop.world_from_unit.to_cols_array_2d(),
                            normals: [normals.x_axis, normals.y_axis, normals.z_axis]
                                .map(|c| c.extend(0.0).to_array()),
                            color: prop.color_linear,
                        }
                    }),
            );
            groups.push(start..u32::try_from(instances.len()).unwrap_or(u32::MAX));
        }
        self.meshes.retain(|gpu| {
            mesh_props
                .iter()
                .any(|prop| std::sync::Arc::ptr_eq(&prop.mesh, &gpu.source))
        });
        let mut meshes = Vec::new();
        for prop in mesh_props
            .iter()
            .filter(|prop| prop.world_from_mesh.is_finite())
        {
            let found = self
                .meshes
                .iter()
                .position(|gpu| std::sync::Arc::ptr_eq(&prop.mesh, &gpu.source));
            let at = found.unwrap_or_else(|| {
                self.meshes.push(GpuPropMesh::new(device, &prop.mesh));
                self.meshes.len() - 1
            });
            let normals = normal_matrix(prop.world_from_mesh);
            let ranges = self.meshes.get(at).map(|gpu| gpu.parts.clone());
            for (range, part) in ranges.into_iter().flatten().zip(&prop.mesh.parts) {
                meshes.push((
                    at,
                    range,
                    u32::try_from(instances.len()).unwrap_or(u32::MAX),
                ));
                instances.push(PropGpuInstance {
                    world_from_unit: prop.world_from_mesh.to_cols_array_2d(),
                    normals: [normals.x_axis, normals.y_axis, normals.z_axis]
                        .map(|c| c.extend(0.0).to_array()),
                    color: part.color_linear,
                });
            }
        }
        if instances.len() > self.capacity {
            self.capacity = instances.len().next_power_of_two();
            self.instances = Self::instance_buffer(device, self.capacity);
        }
        if !instances.is_empty() {
            queue.write_buffer(&self.instances, 0, bytemuck::cast_slice(&instances));
        }
        PropDraws { groups, meshes }
    }

    fn draw(&self, pass: &mut wgpu::RenderPass<'_>, draws: &PropDraws) {
        let groups = &draws.groups;
        if groups.iter().all(std::ops::Range::is_empty) && draws.meshes.is_empty() {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_vertex_buffer(1, self.instances.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        for (indices, instances) in self.ranges.iter().zip(groups) {
            if !instances.is_empty() {
                pass.draw_indexed(indices.clone(), 0, instances.clone());
            }
        }
        for (at, indices, instance) in &draws.meshes {
            if let Some(gpu) = self.meshes.get(*at) {
                pass.set_vertex_buffer(0, gpu.vertices.slice(..));
                pass.set_index_buffer(gpu.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(indices.clone(), 0, *instance..instance.saturating_add(1));
            }
        }
    }
}

/// The colour texture a frame is rendered into, with its multisampled and depth companions.
#[derive(Debug)]
pub struct RenderTarget {
    color: wgpu::Texture,
    color_view: wgpu::TextureView,
    multisampled_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    size_px: [u32; 2],
}

impl RenderTarget {
    /// A target of `size_px` (each side clamped to 1..=max texture size of the device).
    pub fn new(device: &wgpu::Device, size_px: [u32; 2]) -> Self {
        let max_side = device.limits().max_texture_dimension_2d;
        let size_px = size_px.map(|side| side.clamp(1, max_side));
        let extent = wgpu::Extent3d {
            width: size_px[0],
            height: size_px[1],
            depth_or_array_layers: 1,
        };
        let texture = |label, format, sample_count, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: extent,
                mip_level_count: 1,
                sample_count,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let color = texture(
            "stance viewport colour",
            COLOR_FORMAT,
            1,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let multisampled = texture(
            "stance viewport colour (multisampled)",
            COLOR_FORMAT,
            SAMPLE_COUNT,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let depth = texture(
            "stance viewport depth",
            DEPTH_FORMAT,
            SAMPLE_COUNT,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        Self {
            color_view: color.create_view(&wgpu::TextureViewDescriptor::default()),
            multisampled_view: multisampled.create_view(&wgpu::TextureViewDescriptor::default()),
            depth_view: depth.create_view(&wgpu::TextureViewDescriptor::default()),
            color,
            size_px,
        }
    }

    /// Width and height of the target, pixels (after clamping).
    pub fn size_px(&self) -> [u32; 2] {
        self.size_px
    }

    /// The resolved colour texture (format [`COLOR_FORMAT`]).
    pub fn color_texture(&self) -> &wgpu::Texture {
        &self.color
    }

    /// A view of the resolved colour texture, for showing it (e.g. as an egui native texture).
    pub fn color_view(&self) -> &wgpu::TextureView {
        &self.color_view
    }
}

/// Pipelines and buffers, created once; each frame only uploads uniforms and instances.
#[derive(Debug)]
pub struct SceneRenderer {
    capsule_pipeline: wgpu::RenderPipeline,
    skinned_pipeline: SkinnedPipeline,
    avatar: Option<AvatarGpu>,
    /// The cast's models: characters on avatars of their own ([`Scene::cast_poses`]), each
    /// known by its key.
    cast: Vec<CastModel>,
    /// An avatar being uploaded over frames, drawn once complete.
    upload: Option<AvatarUpload>,
    floor_pipeline: wgpu::RenderPipeline,
    frame_uniforms: wgpu::Buffer,
    frame_bind_group: wgpu::BindGroup,
    template_vertices: wgpu::Buffer,
    template_indices: wgpu::Buffer,
    template_index_count: u32,
    instances: wgpu::Buffer,
    instance_capacity: usize,
    props: PropPipeline,
    shadow_uniforms: wgpu::Buffer,
}

/// A unit sphere split at the equator: vertices carry (direction, half) with half 1 for the
/// upper (end) half and 0 for the lower (start) half; the equator appears in both halves so
/// that the strip between them becomes the capsule's cylinder.
fn capsule_template() -> (Vec<[f32; 4]>, Vec<u16>) {
    const RINGS_PER_HALF: u16 = 8;
    const SEGMENTS: u16 = 24;
    let mut vertices = Vec::new();
    let rings = RINGS_PER_HALF * 2 + 2;
    for ring in 0..rings {
        // Upper half: rings 0..=RINGS_PER_HALF (pole to equator); lower half mirrored.
        let (latitude_step, half) = if ring <= RINGS_PER_HALF {
            (ring, 1.0)
        } else {
            (ring - 1, 0.0)
        };
        let polar = std::f32::consts::PI * f32::from(latitude_step) / f32::from(RINGS_PER_HALF * 2);
        let (sin_polar, cos_polar) = polar.sin_cos();
        for segment in 0..=SEGMENTS {
            let azimuth = std::f32::consts::TAU * f32::from(segment) / f32::from(SEGMENTS);
            let (sin_azimuth, cos_azimuth) = azimuth.sin_cos();
            vertices.push([
                sin_polar * cos_azimuth,
                cos_polar,
                sin_polar * sin_azimuth,
                half,
            ]);
        }
    }
    let stride = SEGMENTS + 1;
    let mut indices = Vec::new();
    for ring in 0..rings - 1 {
        for segment in 0..SEGMENTS {
            let a = ring * stride + segment;
            let b = a + stride;
            indices.extend_from_slice(&[a, a + 1, b, a + 1, b + 1, b]);
        }
    }
    (vertices, indices)
}

impl SceneRenderer {
    /// Creates the pipelines (capsules, floor, skinned avatar) and buffers on `device`, with no
    /// avatar uploaded.
    pub fn new(device: &wgpu::Device) -> Self {
        let frame_uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stance frame uniforms"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // The floor's contact shadows: MAX_CONTACT_SHADOWS discs (x, z, radius, strength).
        let shadow_uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stance contact shadows"),
            size: (MAX_CONTACT_SHADOWS * std::mem::size_of::<[f32; 4]>()) as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
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
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("stance frame layout"),
            entries: &[
                uniform_entry(0, wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT),
                uniform_entry(1, wgpu::ShaderStages::FRAGMENT),
            ],
        });
        let frame_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stance frame bind group"),
            layout: &frame_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: frame_uniforms.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: shadow_uniforms.as_entire_binding(),
                },
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stance pipeline layout"),
            bind_group_layouts: &[Some(&frame_layout)],
            immediate_size: 0,
        });
        let shader = |name: &str| {
            let source = SHADERS
                .iter()
                .find(|(file, _)| *file == name)
                .map_or("", |(_, source)| *source);
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(name),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            })
        };
        let capsule_shader = shader("capsule.wgsl");
        let floor_shader = shader("floor.wgsl");
        let skinned_shader = shader("skinned.wgsl");
        let prop_shader = shader("prop.wgsl");
        let depth_stencil = Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        });
        let depth_stencil_for_skinned = depth_stencil.clone();
        let depth_stencil_for_props = depth_stencil.clone();
        let multisample = wgpu::MultisampleState {
            count: SAMPLE_COUNT,
            ..Default::default()
        };
        let color_targets = [Some(wgpu::ColorTargetState {
            format: COLOR_FORMAT,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let template_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<[f32; 4]>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x4],
        };
        let instance_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<CapsuleInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &wgpu::vertex_attr_array![1 => Float32x4, 2 => Float32x4, 3 => Float32x4],
        };
        let capsule_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("stance capsules"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &capsule_shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(template_layout), Some(instance_layout)],
            },
            primitive: wgpu::PrimitiveState {
                // The template's triangles turn counter-clockwise seen from outside (its
                // outward normals by the right-hand rule): their backs, inside, are culled.
                cull_mode: Some(wgpu::Face::Back),
                front_face: wgpu::FrontFace::Ccw,
                ..Default::default()
            },
            depth_stencil: depth_stencil.clone(),
            multisample,
            fragment: Some(wgpu::FragmentState {
                module: &capsule_shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &color_targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        let floor_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("stance floor"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &floor_shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil,
            multisample,
            fragment: Some(wgpu::FragmentState {
                module: &floor_shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &color_targets,
            }),
            multiview_mask: None,
            cache: None,
        });
        let skinned_pipeline = SkinnedPipeline::new(
            device,
            &frame_layout,
            &skinned_shader,
            depth_stencil_for_skinned,
            multisample,
            &color_targets,
        );
        let props = PropPipeline::new(
            device,
            &layout,
            &prop_shader,
            depth_stencil_for_props,
            multisample,
            &color_targets,
        );
        let (template, indices) = capsule_template();
        let template_vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("stance capsule template vertices"),
            contents: bytemuck::cast_slice(&template),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let template_indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("stance capsule template indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let instance_capacity = 128;
        Self {
            capsule_pipeline,
            skinned_pipeline,
            avatar: None,
            cast: Vec::new(),
            upload: None,
            floor_pipeline,
            frame_uniforms,
            frame_bind_group,
            template_vertices,
            template_indices,
            template_index_count: u32::try_from(indices.len()).unwrap_or(0),
            instances: Self::instance_buffer(device, instance_capacity),
            instance_capacity,
            props,
            shadow_uniforms,
        }
    }

    fn instance_buffer(device: &wgpu::Device, capacity: usize) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("stance capsule instances"),
            size: (capacity * std::mem::size_of::<CapsuleInstance>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Uploads an avatar (replacing the previous one), or drops it with `None`.
    pub fn set_avatar(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        model: Option<&SkinnedModel>,
    ) {
        self.upload = None;
        self.avatar =
            model.map(|model| AvatarGpu::new(device, queue, &self.skinned_pipeline, model));
    }

    /// Draws the uploaded avatar's `poses` (none: `0`) and the cast's (`cast_poses`: how many
    /// of each model), then sets the frame's bind group back for the other pipelines.
    fn draw_skinned(&self, pass: &mut wgpu::RenderPass<'_>, poses: usize, cast_poses: &[usize]) {
        if let Some(avatar) = self.avatar.as_ref().filter(|_| poses > 0) {
            for pose in 0..poses {
                avatar.draw(pass, &self.skinned_pipeline, pose);
            }
        }
        for (model, &count) in self.cast.iter().zip(cast_poses) {
            for pose in 0..count {
                model.gpu.draw(pass, &self.skinned_pipeline, pose);
            }
        }
        pass.set_bind_group(0, &self.frame_bind_group, &[]);
    }

    /// Starts uploading `model` over the next frames ([`SceneRenderer::continue_avatar_upload`],
    /// a band of texture rows a step); the avatar uploaded before stays until it is complete.
    pub fn begin_avatar_upload(&mut self, model: std::sync::Arc<SkinnedModel>) {
        self.upload = Some(AvatarUpload::new(model));
    }

    /// One step of the upload begun with [`SceneRenderer::begin_avatar_upload`]: true when the
    /// new avatar is in place (or no upload is under way).
    pub fn continue_avatar_upload(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) -> bool {
        let Some(upload) = &mut self.upload else {
            return true;
        };
        match upload.step(device, queue, &self.skinned_pipeline) {
            Some(avatar) => {
                self.avatar = Some(avatar);
                self.upload = None;
                true
            }
            None => false,
        }
    }

    /// Drops an upload under way.
    pub fn cancel_avatar_upload(&mut self) {
        self.upload = None;
    }

    /// Whether an upload is under way.
    pub fn is_uploading_avatar(&self) -> bool {
        self.upload.is_some()
    }

    /// The uploaded avatar, if any.
    pub fn avatar(&self) -> Option<&AvatarGpu> {
        self.avatar.as_ref()
    }

    /// Renders `scene` seen by `camera` into `target` and submits the work.
    pub fn render(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        target: &RenderTarget,
        camera: &OrbitCamera,
        scene: &Scene,
    ) {
        self.write_frame(queue, target, camera, scene);
        let avatar_poses = self.write_avatar_poses(device, queue, scene);
        let cast_poses = self.write_cast_poses(device, queue, &scene.cast_poses);
        let instance_count = self.write_capsules(device, queue, scene);
        let prop_draws = self
            .props
            .write(device, queue, &scene.props, &scene.mesh_props);

        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("stance frame"),
        });
        {
            let [r, g, b, a] = scene.background_srgb().map(f64::from);
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("stance scene"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target.multisampled_view,
                    depth_slice: None,
                    resolve_target: Some(&target.color_view),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a }),
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &target.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &self.frame_bind_group, &[]);
            self.draw_skinned(&mut pass, avatar_poses, &cast_poses);
            if instance_count > 0 {
                pass.set_pipeline(&self.capsule_pipeline);
                pass.set_vertex_buffer(0, self.template_vertices.slice(..));
                pass.set_vertex_buffer(1, self.instances.slice(..));
                pass.set_index_buffer(self.template_indices.slice(..), wgpu::IndexFormat::Uint16);
                pass.draw_indexed(0..self.template_index_count, 0, 0..instance_count);
            }
            self.props.draw(&mut pass, &prop_draws);
            if scene.show_floor {
                pass.set_pipeline(&self.floor_pipeline);
                pass.draw(0..6, 0..1);
            }
        }
        queue.submit([encoder.finish()]);
    }

    /// Writes the frame's uniforms (camera, light, background, control map) and contact
    /// shadows.
    fn write_frame(
        &self,
        queue: &wgpu::Queue,
        target: &RenderTarget,
        camera: &OrbitCamera,
        scene: &Scene,
    ) {
        let [width, height] = target.size_px;
        let aspect = Vec2::new(width as f32, height as f32);
        let uniforms = FrameUniforms {
            clip_from_world: camera
                .clip_from_world(aspect.x / aspect.y)
                .to_cols_array_2d(),
            camera_position_world: camera.eye_world().extend(1.0).to_array(),
            light_direction_world: LIGHT_DIRECTION_WORLD,
            background: scene.background_srgb(),
            view_from_world: camera.view_from_world().to_cols_array_2d(),
            control_map: scene.shading.uniform(),
        };
        queue.write_buffer(&self.frame_uniforms, 0, bytemuck::bytes_of(&uniforms));
        let mut shadows = [[0.0f32; 4]; MAX_CONTACT_SHADOWS];
        for (slot, shadow) in shadows.iter_mut().zip(
            scene
                .shadows
                .iter()
                .filter(|s| s.centre_xz.iter().all(|v| v.is_finite()) && s.radius_m > 0.0),
        ) {
            *slot = [
                shadow.centre_xz[0],
                shadow.centre_xz[1],
                shadow.radius_m,
                shadow.strength.clamp(0.0, 1.0),
            ];
        }
        queue.write_buffer(&self.shadow_uniforms, 0, bytemuck::cast_slice(&shadows));
    }

    /// Writes the uploaded avatar's poses when the scene shows it; returns how many to draw
    /// (0: none).
    fn write_avatar_poses(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
    ) -> usize {
        let Some(avatar) = self.avatar.as_mut().filter(|_| scene.show_avatar) else {
            return 0;
        };
        // No palettes of its own: the avatar's first pose is not drawn, the others are (the
        // characters on the same model while the selected one is drawn otherwise).
        let first = Some(&scene.avatar_palettes).filter(|palettes| !palettes.is_empty());
        let poses: Vec<&Vec<Vec<glam::Mat4>>> =
            first.into_iter().chain(&scene.more_avatar_poses).collect();
        avatar.ensure_poses(device, &self.skinned_pipeline, poses.len());
        for (pose, palettes) in poses.iter().enumerate() {
            avatar.write_palettes(queue, pose, palettes);
        }
        poses.len()
    }

    /// Writes the instances of the scene's capsules and markers; returns how many.
    fn write_capsules(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, scene: &Scene) -> u32 {
        let instances: Vec<CapsuleInstance> = scene
            .capsules
            .iter()
            .chain(&scene.markers)
            .filter(|capsule| {
                capsule.start_world.is_finite()
                    && capsule.end_world.is_finite()
                    && capsule.radius_m.is_finite()
            })
            .map(|capsule| CapsuleInstance {
                start_and_radius: capsule.start_world.extend(capsule.radius_m).to_array(),
                end_world: capsule.end_world.extend(1.0).to_array(),
                color: capsule.color_linear,
            })
            .collect();
        if instances.len() > self.instance_capacity {
            self.instance_capacity = instances.len().next_power_of_two();
            self.instances = Self::instance_buffer(device, self.instance_capacity);
        }
        if !instances.is_empty() {
            queue.write_buffer(&self.instances, 0, bytemuck::cast_slice(&instances));
        }
        u32::try_from(instances.len()).unwrap_or(u32::MAX)
    }
}
