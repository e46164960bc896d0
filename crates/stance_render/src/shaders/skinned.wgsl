// Skinned, textured meshes (avatars): linear blend skinning with up to four joints per
// vertex, from a palette of at most 256 matrices in a uniform buffer (WebGL2 has no storage
// buffers). Matrices map the mesh's space to the H-Anim world (+Y up, metres).

struct Palette {
    world_from_mesh: array<mat4x4<f32>, 256>,
};

struct Material {
    // Linear RGBA factor multiplied with the texture.
    base_color: vec4<f32>,
    // x: 1 when unlit, y: alpha cutoff (0 = opaque).
    params: vec4<f32>,
};

@group(1) @binding(0) var<uniform> palette: Palette;
@group(2) @binding(0) var<uniform> material: Material;
@group(2) @binding(1) var base_texture: texture_2d<f32>;
@group(2) @binding(2) var base_sampler: sampler;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) joints: vec4<u32>,
    @location(4) weights: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) normal_world: vec3<f32>,
    @location(1) position_world: vec3<f32>,
    @location(2) uv: vec2<f32>,
};

fn palette_matrix(index: u32) -> mat4x4<f32> {
    return palette.world_from_mesh[min(index, 255u)];
}

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    let skin = palette_matrix(in.joints.x) * in.weights.x
        + palette_matrix(in.joints.y) * in.weights.y
        + palette_matrix(in.joints.z) * in.weights.z
        + palette_matrix(in.joints.w) * in.weights.w;
    let position = skin * vec4<f32>(in.position, 1.0);
    let normal = (skin * vec4<f32>(in.normal, 0.0)).xyz;
    var out: VertexOut;
    out.clip_position = frame.clip_from_world * position;
    out.position_world = position.xyz;
    out.normal_world = normal;
    out.uv = in.uv;
    return out;
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front_facing: bool) -> @location(0) vec4<f32> {
    let texel = textureSample(base_texture, base_sampler, in.uv);
    let albedo = texel * material.base_color;
    if (material.params.y > 0.0 && albedo.a < material.params.y) {
        discard;
    }
    var n = normalize(in.normal_world);
    if (!front_facing) {
        n = -n;
    }
    if (frame.control_map.x > 0.5) {
        return control_map_color(in.position_world, n);
    }
    if (material.params.x > 0.5) {
        return vec4<f32>(linear_to_srgb(albedo.rgb), 1.0);
    }
    let l = normalize(-frame.light_direction_world.xyz);
    let v = normalize(frame.camera_position_world.xyz - in.position_world);
    let h = normalize(l + v);
    let sky = mix(0.22, 0.4, n.y * 0.5 + 0.5);
    let diffuse = max(dot(n, l), 0.0) * 0.75;
    let specular = pow(max(dot(n, h), 0.0), 32.0) * 0.04;
    let linear = albedo.rgb * (sky + diffuse) + vec3<f32>(specular);
    return vec4<f32>(linear_to_srgb(linear), 1.0);
}
