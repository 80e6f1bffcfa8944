// The scene: the floor, the character's planar shadow, the lit character,
// and 2-D overlays in picture pixels. One uniform block for every pass.

struct Globals {
    // World -> clip, the output rotation folded in.
    view_proj: mat4x4<f32>,
    // World -> clip after flattening onto the floor along the light.
    shadow_view_proj: mat4x4<f32>,
    // Picture pixels (origin top left, y down) -> clip, rotation folded in.
    screen: mat4x4<f32>,
    eye: vec4<f32>,
    // Unit vector towards the light.
    light: vec4<f32>,
    // rgb: the background the floor fades into; a: where fading starts (m).
    fog: vec4<f32>,
};

@group(0) @binding(0) var<uniform> g: Globals;

struct VertexIn {
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
};

struct Surface {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
};

@vertex
fn vs_lit(v: VertexIn) -> Surface {
    var out: Surface;
    out.clip = g.view_proj * vec4<f32>(v.pos, 1.0);
    out.world = v.pos;
    out.normal = v.normal;
    out.color = v.color;
    return out;
}

fn fog_amount(world: vec3<f32>) -> f32 {
    let d = length(world - g.eye.xyz);
    return smoothstep(g.fog.a, g.fog.a * 3.0, d);
}

// Character and boxes: sky/ground ambient, a warm key light, a little
// specular and a cool rim so that limbs read against the floor.
@fragment
fn fs_lit(s: Surface) -> @location(0) vec4<f32> {
    let n = normalize(s.normal);
    let l = g.light.xyz;
    let v = normalize(g.eye.xyz - s.world);
    let h = normalize(l + v);
    let ambient = mix(vec3<f32>(0.20, 0.18, 0.17), vec3<f32>(0.38, 0.42, 0.50), n.y * 0.5 + 0.5);
    let diffuse = max(dot(n, l), 0.0) * vec3<f32>(1.0, 0.95, 0.88);
    let spec = pow(max(dot(n, h), 0.0), 40.0) * 0.25;
    let rim = pow(1.0 - max(dot(n, v), 0.0), 3.0) * 0.30;
    let base = s.color.rgb;
    var c = base * (ambient + diffuse) + vec3<f32>(spec) + rim * vec3<f32>(0.55, 0.65, 0.85);
    // Highlight: the part glows in its own colour.
    c = mix(c, base * 0.8 + vec3<f32>(0.25, 0.18, 0.05) + rim, s.color.a);
    return vec4<f32>(mix(c, g.fog.rgb, fog_amount(s.world)), 1.0);
}

// The floor: 0.5 m tiles in two tones with anti-aliased joints, fading
// into the background with distance.
@fragment
fn fs_floor(s: Surface) -> @location(0) vec4<f32> {
    let p = s.world.xz / 0.5;
    let cell = floor(p);
    let checker = (i32(cell.x) + i32(cell.y)) & 1;
    var base = s.color.rgb * select(1.0, 0.86, checker == 1);
    let f = fwidth(p);
    let edge = abs(fract(p - 0.5) - 0.5) / max(f, vec2<f32>(1e-4));
    let line = 1.0 - min(min(edge.x, edge.y), 1.0);
    base = mix(base, base * 0.6, line);
    let light = 0.75 + 0.25 * max(g.light.y, 0.0);
    return vec4<f32>(mix(base * light, g.fog.rgb, fog_amount(s.world)), 1.0);
}

struct Flat {
    @builtin(position) clip: vec4<f32>,
    @location(0) fog: f32,
};

@vertex
fn vs_shadow(v: VertexIn) -> Flat {
    var out: Flat;
    out.clip = g.shadow_view_proj * vec4<f32>(v.pos, 1.0);
    out.fog = fog_amount(v.pos);
    return out;
}

// Each pixel is darkened once (the stencil keeps overlapping parts from
// darkening it twice).
@fragment
fn fs_shadow(s: Flat) -> @location(0) vec4<f32> {
    return vec4<f32>(0.0, 0.0, 0.02, 0.42 * (1.0 - s.fog));
}

struct OverlayIn {
    @location(0) pos: vec2<f32>,
    @location(1) color: vec4<f32>,
};

struct OverlayOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
};

@vertex
fn vs_overlay(v: OverlayIn) -> OverlayOut {
    var out: OverlayOut;
    out.clip = g.screen * vec4<f32>(v.pos, 0.0, 1.0);
    out.color = v.color;
    return out;
}

@fragment
fn fs_overlay(s: OverlayOut) -> @location(0) vec4<f32> {
    return s.color;
}
