// Mirrors dirt_math::triangle line for line: the watertight ray/triangle test
// (Woop, Benthin, Wald 2013) with sign-accurate edge functions and the
// on-triangle check. Every `/` of the Rust is div_cr here.
#import types
#import num
#import divide

struct RayShear {
    kx: u32,
    ky: u32,
    kz: u32,
    sx: f32,
    sy: f32,
    sz: f32,
}

fn ray_shear(ray: Ray) -> RayShear {
    let d = ray.dir;
    let ax = abs(d[0]);
    let ay = abs(d[1]);
    let az = abs(d[2]);
    var kz = 2u;
    if (ax >= ay) & (ax >= az) {
        kz = 0u;
    } else if ay >= az {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if d[kz] < 0.0 {
        let tmp = kx;
        kx = ky;
        ky = tmp;
    }
    return RayShear(kx, ky, kz, div_cr(d[kx], d[kz]), div_cr(d[ky], d[kz]), div_cr(1.0, d[kz]));
}

// Veltkamp split: a = hi + lo exactly.
fn split_hi(a: f32) -> f32 {
    let c = 4097.0 * a;
    return c - (c - a);
}

// Dekker's product: returns (p, e) with a*b = p + e exactly.
fn two_product(a: f32, b: f32) -> vec2<f32> {
    let p = a * b;
    let ah = split_hi(a);
    let al = a - ah;
    let bh = split_hi(b);
    let bl = b - bh;
    let e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    return vec2<f32>(p, e);
}

fn diff_of_products(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let p = two_product(a, b);
    let q = two_product(c, d);
    return (p.x - q.x) + (p.y - q.y);
}

fn edge_function(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let p = a * b;
    let q = c * d;
    let e = p - q;
    if abs(e) >= (abs(p) + abs(q)) * 0.03125 {
        return e;
    }
    return diff_of_products(a, b, c, d);
}

// (hit, t, u, v) packed: x = 1.0 when hit.
struct TriHit {
    hit: bool,
    t: f32,
    u: f32,
    v: f32,
}

fn intersect(ray: Ray, sh: RayShear, v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>) -> TriHit {
    let miss = TriHit(false, 0.0, 0.0, 0.0);
    let o = ray.origin;
    let kx = sh.kx;
    let ky = sh.ky;
    let kz = sh.kz;
    let a = vec3<f32>(v0[0] - o[0], v0[1] - o[1], v0[2] - o[2]);
    let b = vec3<f32>(v1[0] - o[0], v1[1] - o[1], v1[2] - o[2]);
    let c = vec3<f32>(v2[0] - o[0], v2[1] - o[1], v2[2] - o[2]);
    let ax = a[kx] - sh.sx * a[kz];
    let ay = a[ky] - sh.sy * a[kz];
    let bx = b[kx] - sh.sx * b[kz];
    let by = b[ky] - sh.sy * b[kz];
    let cx = c[kx] - sh.sx * c[kz];
    let cy = c[ky] - sh.sy * c[kz];
    let e0 = edge_function(cx, by, cy, bx);
    let e1 = edge_function(ax, cy, ay, cx);
    let e2 = edge_function(bx, ay, by, ax);
    if ((e0 < 0.0) | (e1 < 0.0) | (e2 < 0.0)) & ((e0 > 0.0) | (e1 > 0.0) | (e2 > 0.0)) {
        return miss;
    }
    let det = e0 + e1 + e2;
    if (det == 0.0) | (det != det) {
        return miss;
    }
    let az = sh.sz * a[kz];
    let bz = sh.sz * b[kz];
    let cz = sh.sz * c[kz];
    let tt = e0 * az + e1 * bz + e2 * cz;
    let t = div_cr(tt, det);
    if !((t >= ray.tmin) & (t <= ray.tmax)) {
        return miss;
    }
    let u = div_cr(e1, det);
    let v = div_cr(e2, det);
    let d = ray.dir;
    // The loop over k = 0, 1, 2 of the Rust, unrolled: lavapipe caps the
    // loop iterations of a whole invocation.
    let y0 = a[0] + u * (b[0] - a[0]) + v * (c[0] - a[0]);
    var err = fmax(0.0, abs(t * d[0] - y0));
    var size = fmax(fmax(fmax(0.0, abs(a[0])), abs(b[0])), abs(c[0]));
    let y1 = a[1] + u * (b[1] - a[1]) + v * (c[1] - a[1]);
    err = fmax(err, abs(t * d[1] - y1));
    size = fmax(fmax(fmax(size, abs(a[1])), abs(b[1])), abs(c[1]));
    let y2 = a[2] + u * (b[2] - a[2]) + v * (c[2] - a[2]);
    err = fmax(err, abs(t * d[2] - y2));
    size = fmax(fmax(fmax(size, abs(a[2])), abs(b[2])), abs(c[2]));
    if !(err <= size * 0.000030517578125) {
        return miss;
    }
    if is_degenerate(v0, v1, v2) {
        return miss;
    }
    return TriHit(true, t, u, v);
}

// dirt_math::triangle::is_degenerate: the edge vectors' cross product is exactly zero.
fn is_degenerate(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>) -> bool {
    let e = vec3<f32>(v1[0] - v0[0], v1[1] - v0[1], v1[2] - v0[2]);
    let f = vec3<f32>(v2[0] - v0[0], v2[1] - v0[1], v2[2] - v0[2]);
    let nx = edge_function(e[1], f[2], e[2], f[1]);
    let ny = edge_function(e[2], f[0], e[0], f[2]);
    let nz = edge_function(e[0], f[1], e[1], f[0]);
    return (nx == 0.0) & (ny == 0.0) & (nz == 0.0);
}
