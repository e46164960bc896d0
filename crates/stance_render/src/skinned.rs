//! Skinned, textured avatars: the model's vertices, indices, materials and textures, as the
//! GPU takes them (uploaded by `skinned_gpu`; plain data here, without wgpu).

use bytemuck::{Pod, Zeroable};

/// Most matrices one palette (one skin) may hold: a 16 KiB uniform buffer, the WebGL2 limit.
pub const MAX_PALETTE_MATRICES: usize = 256;

/// One vertex of a skinned mesh, in the mesh's own space.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct SkinnedVertex {
    /// Position in mesh space.
    pub position: [f32; 3],
    /// Unit normal in mesh space.
    pub normal: [f32; 3],
    /// Texture coordinates (glTF convention: v down the image).
    pub uv: [f32; 2],
    /// Indices into the primitive's palette.
    pub joints: [u32; 4],
    /// Blend weights (sum 1).
    pub weights: [f32; 4],
}

/// A triangle list drawn with one material and one palette.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SkinnedPrimitive {
    /// The primitive's vertices.
    pub vertices: Vec<SkinnedVertex>,
    /// Triangle list: three indices into `vertices` per triangle.
    pub indices: Vec<u32>,
    /// Index into [`SkinnedModel::materials`] (out of range: a plain grey material).
    pub material: usize,
    /// Index of the palette (matrices set each frame) that moves this primitive.
    pub palette: usize,
}

/// A material: base colour factor and optional texture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkinnedMaterial {
    /// Linear RGBA.
    pub base_color_factor: [f32; 4],
    /// Index into [`SkinnedModel::textures`].
    pub texture: Option<usize>,
    /// Draw without lighting: the base colour as is (glTF `KHR_materials_unlit`).
    pub unlit: bool,
    /// Alpha below this is discarded (`None`: opaque).
    pub alpha_cutoff: Option<f32>,
}

/// An RGBA8 texture (sRGB), rows top to bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct SkinnedTexture {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// `width * height * 4` bytes (shared with the avatar they come from).
    pub rgba8: std::sync::Arc<Vec<u8>>,
    /// Sample with repeat wrapping; otherwise clamp to the edge.
    pub repeat: bool,
}

/// Everything the GPU needs of an avatar.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SkinnedModel {
    /// The triangle lists to draw.
    pub primitives: Vec<SkinnedPrimitive>,
    /// Materials the primitives refer to by index.
    pub materials: Vec<SkinnedMaterial>,
    /// Textures the materials refer to by index.
    pub textures: Vec<SkinnedTexture>,
    /// Matrices per palette.
    pub palette_sizes: Vec<usize>,
}
