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

// A skinned figure's joint: its skinning matrix (rest pose to posed) and
// x: whether it glows; yzw: the figure's tint (its first joint's; y < 0
// when none).
struct Joint {
    skin: mat4x4<f32>,
    extra: vec4<f32>,
};

@group(1) @binding(0) var<storage, read> joints: array<Joint>;

struct SkinIn {
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) plain: vec3<f32>,
    // rgb + a * tint where the figure is tinted.
    @location(3) tinted: vec4<f32>,
    @location(4) joint: vec4<u32>,
    @location(5) weight: vec4<f32>,
    @location(6) glow: u32,
    // The figure's first joint in `joints`.
    @builtin(instance_index) base: u32,
};

// Linear blend skinning: the rest-pose vertex and normal carried by up to
// four joints, their matrices blended by the weights (no branches: a
// joint of weight 0 adds nothing).
@vertex
fn vs_skinned(v: SkinIn) -> Surface {
    let m = v.weight.x * joints[v.base + v.joint.x].skin
        + v.weight.y * joints[v.base + v.joint.y].skin
        + v.weight.z * joints[v.base + v.joint.z].skin
        + v.weight.w * joints[v.base + v.joint.w].skin;
    let p = (m * vec4<f32>(v.pos, 1.0)).xyz;
    let n = (m * vec4<f32>(v.normal, 0.0)).xyz;
    let tint = joints[v.base].extra;
    var rgb = v.plain;
    if (tint.y >= 0.0) {
        rgb = v.tinted.rgb + v.tinted.a * tint.yzw;
    }
    var out: Surface;
    out.clip = g.view_proj * vec4<f32>(p, 1.0);
    out.world = p;
    // Unit at each vertex, as the other meshes' normals are.
    out.normal = normalize(n);
    out.color = vec4<f32>(rgb, joints[v.base + v.glow].extra.x);
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
