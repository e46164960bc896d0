// Shaded capsules: one instance per bone, built from a unit sphere template whose upper
// half follows the bone's end and lower half its start.

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

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return lit_color(in.normal_world, in.position_world, in.color);
}
