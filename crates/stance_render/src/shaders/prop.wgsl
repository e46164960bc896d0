// Shaded props: instances of a unit shape (box, sphere, cylinder), each placed, turned and
// sized by its matrix; lit like the capsules.

struct Frame {
    clip_from_world: mat4x4<f32>,
    camera_position_world: vec4<f32>,
    light_direction_world: vec4<f32>,
    background: vec4<f32>,
    view_from_world: mat4x4<f32>,
    // A control map instead of the shaded picture: x 0 shaded, 1 depth, 2 normals, 3 mask;
    // y, z: the depth (m along the view) drawn white and black.
    control_map: vec4<f32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;

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

fn linear_to_srgb(linear: vec3<f32>) -> vec3<f32> {
    let c = clamp(linear, vec3<f32>(0.0), vec3<f32>(1.0));
    let low = c * 12.92;
    let high = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(high, low, c <= vec3<f32>(0.0031308));
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let n = normalize(in.normal_world);
    if (frame.control_map.x > 0.5) {
        return control_map_color(in.position_world, n);
    }
    let l = normalize(-frame.light_direction_world.xyz);
    let v = normalize(frame.camera_position_world.xyz - in.position_world);
    let h = normalize(l + v);
    let sky = mix(0.18, 0.32, n.y * 0.5 + 0.5);
    let diffuse = max(dot(n, l), 0.0) * 0.75;
    let specular = pow(max(dot(n, h), 0.0), 16.0) * 0.04;
    let albedo = in.color.rgb;
    let linear = albedo * (sky + diffuse) + vec3<f32>(specular);
    return vec4<f32>(linear_to_srgb(linear), in.color.a);
}
