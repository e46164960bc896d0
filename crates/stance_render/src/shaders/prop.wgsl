// Shaded props: instances of a unit shape (box, sphere, cylinder), each placed, turned and
// sized by its matrix; lit like the capsules (`lit.wgsl.part`).

struct VertexIn {
    // The unit shape's point and outward normal.
    @location(0) position_unit: vec4<f32>,
    @location(1) normal_unit: vec4<f32>,
    // world_from_unit, by columns.
    @location(2) column_0: vec4<f32>,
    @location(3) column_1: vec4<f32>,
    @location(4) column_2: vec4<f32>,
    @location(5) column_3: vec4<f32>,
    // The normals' matrix (the inverse transpose of world_from_unit's 3x3), by columns.
    @location(6) normal_0: vec4<f32>,
    @location(7) normal_1: vec4<f32>,
    @location(8) normal_2: vec4<f32>,
    @location(9) color: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) normal_world: vec3<f32>,
    @location(1) position_world: vec3<f32>,
    @location(2) color: vec4<f32>,
};

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    let world_from_unit = mat4x4<f32>(in.column_0, in.column_1, in.column_2, in.column_3);
    let normals = mat3x3<f32>(in.normal_0.xyz, in.normal_1.xyz, in.normal_2.xyz);
    let position = (world_from_unit * vec4<f32>(in.position_unit.xyz, 1.0)).xyz;
    var out: VertexOut;
    out.clip_position = frame.clip_from_world * vec4<f32>(position, 1.0);
    out.normal_world = normalize(normals * in.normal_unit.xyz);
    out.position_world = position;
    out.color = in.color;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return lit_color(in.normal_world, in.position_world, in.color);
}
