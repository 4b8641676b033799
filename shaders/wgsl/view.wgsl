// Mirrors dirt_math::view: view-space transforms and tile boundaries.
#import types
#import num
#import divide

const EPS_RAY_REL: f32 = 0.000244140625; // 2^-12

// dirt_math::ViewRay
struct ViewRay {
    o: vec3<f32>,
    d: vec3<f32>,
    eps: f32,
}

fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

fn to_view(v: View, p: vec3<f32>) -> vec3<f32> {
    let q = vec3<f32>(p[0] - v.apex[0], p[1] - v.apex[1], p[2] - v.apex[2]);
    return vec3<f32>(dot3(q, v.right), dot3(q, v.up), dot3(q, v.forward));
}

fn dir_to_view(v: View, d: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot3(d, v.right), dot3(d, v.up), dot3(d, v.forward));
}

fn view_ray(v: View, ray: Ray) -> ViewRay {
    let o = to_view(v, ray.origin);
    let d = dir_to_view(v, ray.dir);
    let m = fmax(fmax(abs(o[0]), abs(o[1])), abs(o[2]));
    return ViewRay(o, d, EPS_RAY_REL * (m + 2.0 * v.scale));
}

// dirt_math::View::w: the divisor of image coordinates at depth z (the depth
// clamped to near/2 in a perspective view, exactly 1 in an orthographic one).
fn view_w(v: View, z: f32) -> f32 {
    if v.ortho != 0u {
        return 1.0;
    }
    return fmax(z, v.near * 0.5);
}

// Slope of tile boundary k.
fn boundary(v: View, k: u32) -> f32 {
    return f32(k) * v.step - v.tan;
}

// Continuous tile coordinate of slope s.
fn tile_coord(v: View, s: f32) -> f32 {
    return div_cr(s + v.tan, v.step);
}

fn tile_count(v: View) -> u32 {
    return v.tiles * v.tiles;
}
