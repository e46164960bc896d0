// Shaded capsules: one instance per bone, built from a unit sphere template whose upper
// half follows the bone's end and lower half its start.

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
    // xyz: unit direction on the template sphere; w: 1 on the end half, 0 on the start half.
    @location(0) template_direction: vec4<f32>,
    // xyz: start of the segment (world); w: radius (metres).
    @location(1) start_and_radius: vec4<f32>,
    @location(2) end_world: vec4<f32>,
    @location(3) color: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) normal_world: vec3<f32>,
    @location(1) position_world: vec3<f32>,
    @location(2) color: vec4<f32>,
};

@vertex
fn vs_main(in: VertexIn) -> VertexOut {
    let start = in.start_and_radius.xyz;
    let radius = in.start_and_radius.w;
    let end = in.end_world.xyz;
    let axis = end - start;
    let length_m = length(axis);
    var y_axis = vec3<f32>(0.0, 1.0, 0.0);
    if (length_m > 1e-6) {
        y_axis = axis / length_m;
    }
    var helper = vec3<f32>(1.0, 0.0, 0.0);
    if (abs(y_axis.x) > 0.9) {
        helper = vec3<f32>(0.0, 0.0, 1.0);
    }
    let x_axis = normalize(cross(helper, y_axis));
    let z_axis = cross(x_axis, y_axis);
    let d = in.template_direction.xyz;
    let normal = normalize(x_axis * d.x + y_axis * d.y + z_axis * d.z);
    let anchor = mix(start, end, in.template_direction.w);
    let position = anchor + normal * radius;

    var out: VertexOut;
    out.clip_position = frame.clip_from_world * vec4<f32>(position, 1.0);
    out.normal_world = normal;
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
    // Hemisphere ambient (sky above, floor bounce below) + key light + a soft rim.
    let sky = mix(0.16, 0.3, n.y * 0.5 + 0.5);
    let diffuse = max(dot(n, l), 0.0) * 0.8;
    let specular = pow(max(dot(n, h), 0.0), 24.0) * 0.06;
    let rim = pow(1.0 - max(dot(n, v), 0.0), 3.0) * 0.08;
    let albedo = in.color.rgb;
    let linear = albedo * (sky + diffuse + rim) + vec3<f32>(specular);
    return vec4<f32>(linear_to_srgb(linear), in.color.a);
}
