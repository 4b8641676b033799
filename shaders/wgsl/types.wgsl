// GPU structs. Each is declared once in Rust (dirt-math `types`), and a test
// compares size and offsets with these declarations as naga sees them.

// dirt_math::Ray (32 bytes)
struct Ray {
    origin: vec3<f32>,
    tmin: f32,
    dir: vec3<f32>,
    tmax: f32,
}

// dirt_math::Hit (16 bytes); prim == 0xffffffff is a miss.
struct Hit {
    prim: u32,
    t: f32,
    u: f32,
    v: f32,
}

// dirt_math::ViewGpu (96 bytes)
struct View {
    apex: vec3<f32>,
    tan: f32,
    right: vec3<f32>,
    near: f32,
    up: vec3<f32>,
    far: f32,
    forward: vec3<f32>,
    eps: f32,
    tiles: u32,
    step: f32,
    scale: f32,
    // View::slot: this view's block in the per-tile buffers; NO_SLOT = no content.
    slot: u32,
    adjacency: vec4<u32>,
    // View::ortho: 1 for an orthographic view (dirt_math::view).
    ortho: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// dirt_math::RayStats (16 bytes)
struct RayStats {
    views: u32,
    tiles: u32,
    buckets: u32,
    tests: u32,
}

const INVALID_ID: u32 = 0xffffffffu;
// dirt_math::view::NO_SLOT
const NO_SLOT: u32 = 0xffffffffu;
// dirt_gpu::UNFINISHED: the trace ran out of its work budget (work.wgsl).
const UNFINISHED_ID: u32 = 0xfffffffeu;
// dirt_gpu::STRUCTURE_FULL: the structure's lists did not fit their ids.
const STRUCTURE_FULL_ID: u32 = 0xfffffffdu;

// The largest finite f32, exactly (the decimal 3.4028235e38 is above it, and
// Tint refuses a literal that f32 cannot represent).
const F32_MAX: f32 = 0x1.fffffep+127f;

// WGSL has no infinity literal, and a constant expression may not evaluate
// to one (Tint refuses the shader; naga folds it): make them from bits held
// in a `let`, which makes the bitcast a run-time expression.
fn f32_inf() -> f32 {
    let bits = 0x7f800000u;
    return bitcast<f32>(bits);
}
fn f32_neg_inf() -> f32 {
    let bits = 0xff800000u;
    return bitcast<f32>(bits);
}

// A miss (dirt_math::Hit::MISS).
fn hit_miss() -> Hit {
    return Hit(INVALID_ID, f32_inf(), 0.0, 0.0);
}

fn hit_is_hit(h: Hit) -> bool {
    return h.prim != INVALID_ID;
}

// The deterministic order of the design brief §2: smaller t, then smaller id.
fn hit_closer_than(a: Hit, b: Hit) -> bool {
    return (a.t < b.t) | ((a.t == b.t) & (a.prim < b.prim));
}
