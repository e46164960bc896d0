// The floor: a large square at y = 0 with a metre grid, decimetre lines near the camera,
// the X axis in red and the Z axis in blue, soft contact shadows under what stands on it,
// fading into the background with distance.

// Contact shadows: x, z of the centre, radius (m), strength (0: none).
@group(0) @binding(1) var<uniform> shadows: array<vec4<f32>, 16>;

const HALF_EXTENT_M: f32 = 50.0;

struct VertexOut {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) position_world: vec3<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vertex_index: u32) -> VertexOut {
    // Two triangles covering the square.
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    let corner = corners[vertex_index] * HALF_EXTENT_M;
    let position = vec3<f32>(corner.x, 0.0, corner.y);
    var out: VertexOut;
    out.clip_position = frame.clip_from_world * vec4<f32>(position, 1.0);
    out.position_world = position;
    return out;
}

fn grid_line(coordinate: vec2<f32>, spacing: f32) -> f32 {
    let scaled = coordinate / spacing;
    let width = fwidth(scaled);
    let distance_to_line = abs(fract(scaled - 0.5) - 0.5) / max(width, vec2<f32>(1e-4));
    return 1.0 - min(min(distance_to_line.x, distance_to_line.y), 1.0);
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let xz = in.position_world.xz;
    let major = grid_line(xz, 1.0);
    let minor = grid_line(xz, 0.1) * 0.35;
    let line = max(major, minor);
    var color = vec3<f32>(0.055, 0.06, 0.07);
    color = mix(color, vec3<f32>(0.2, 0.21, 0.23), line);
    // Soft dark discs under the characters and props (darker the nearer they rest), on the
    // grid, not on the axes.
    var light = 1.0;
    for (var i = 0; i < 16; i = i + 1) {
        let shadow = shadows[i];
        if (shadow.w > 0.0 && shadow.z > 0.0) {
            let d = length(xz - shadow.xy) / shadow.z;
            light = light * (1.0 - 0.85 * shadow.w * (1.0 - smoothstep(0.0, 1.0, d)));
        }
    }
    color = color * light;

    let axis_width = fwidth(xz) * 1.5;
    if (abs(xz.y) < axis_width.y) {
        color = vec3<f32>(0.55, 0.12, 0.12);
    }
    if (abs(xz.x) < axis_width.x) {
        color = vec3<f32>(0.12, 0.2, 0.6);
    }
    let distance_m = length(in.position_world - frame.camera_position_world.xyz);
    let fade = smoothstep(8.0, 30.0, distance_m);
    // Into the background, alpha too: a transparent background (0, 0, 0, 0) leaves the
    // distant floor transparent, premultiplied like the multisample resolve's edges.
    let srgb = mix(linear_to_srgb(color), frame.background.rgb, fade);
    return vec4<f32>(srgb, mix(1.0, frame.background.a, fade));
}
