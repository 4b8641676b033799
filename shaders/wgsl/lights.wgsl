// Mirrors dirt_render::lights: choosing a light and a point on it. Reads the
// globals `params`, `lights` and `tris` of the stage that imports it.

#import render_types

const LIGHT_AREA: u32 = 0u;
const LIGHT_POINT: u32 = 1u;
const LIGHT_SPOT: u32 = 2u;
const LIGHT_DIRECTIONAL: u32 = 3u;

struct LightSample {
    // LIGHT_AREA, LIGHT_POINT (point and spot) or LIGHT_DIRECTIONAL.
    kind: u32,
    // Area: the triangle; punctual: the index among the punctual lights.
    index: u32,
    point: vec3<f32>,
    // Area: the unit normal; directional: the light's direction.
    normal: vec3<f32>,
    // Area: emitted radiance; point: intensity; directional: irradiance.
    radiance: vec3<f32>,
    // Area: the area pdf (choice included); punctual: the probability of the pick.
    pdf: f32,
}

fn tri_area(t: TriGpu) -> f32 {
    let c = cross(t.p1 - t.p0, t.p2 - t.p0);
    return 0.5 * sqrt(dot3(c, c));
}

// Lights::pdf_area.
fn light_pdf_area(prim: u32) -> f32 {
    if prim >= params.n_tris {
        return 0.0;
    }
    let t = tris[prim];
    if t.light_prob == 0.0 {
        return 0.0;
    }
    let a = tri_area(t);
    return select(0.0, params.p_area * t.light_prob / a, a > 0.0);
}

// Lights::sample, for a scene with lights.
fn light_sample(u0: f32, u1: f32, u2: f32) -> LightSample {
    if u0 < params.p_area {
        let x = u0 / params.p_area;
        // partition_point(|c| c <= x) over the cumulative powers.
        var lo = 0u;
        var hi = params.n_area;
        while lo < hi {
            let mid = (lo + hi) / 2u;
            if lights[mid].cdf <= x {
                lo = mid + 1u;
            } else {
                hi = mid;
            }
        }
        let l = lights[min(lo, params.n_area - 1u)];
        let t = tris[l.prim];
        let su = sqrt(u1);
        let point = t.p0 * (1.0 - su) + t.p1 * (su * (1.0 - u2)) + t.p2 * (su * u2);
        let normal = normalize_or_zero(cross(t.p1 - t.p0, t.p2 - t.p0));
        return LightSample(LIGHT_AREA, l.prim, point, normal, l.color, params.p_area * t.light_prob / l.area);
    }
    let n = params.n_punctual;
    let x = (u0 - params.p_area) / (1.0 - params.p_area);
    let i = min(u32(x * f32(n)), n - 1u);
    let l = lights[params.n_area + i];
    let pick = (1.0 - params.p_area) / f32(n);
    if l.kind == LIGHT_DIRECTIONAL {
        return LightSample(LIGHT_DIRECTIONAL, i, vec3<f32>(0.0), l.direction, l.color, pick);
    }
    return LightSample(LIGHT_POINT, i, l.position, vec3<f32>(0.0), l.color, pick);
}

// Lights::punctual_factor: the spot cone and the range window.
fn punctual_factor(l: LightGpu, to_point: vec3<f32>, dist: f32) -> f32 {
    var f = 1.0;
    if l.kind == LIGHT_SPOT {
        let cd = dot3(l.direction, to_point);
        let scale = 1.0 / max(l.cos_inner - l.cos_outer, 1e-4);
        let t = clamp((cd - l.cos_outer) * scale, 0.0, 1.0);
        f *= t * t;
    }
    if l.range > 0.0 {
        let x = dist / l.range;
        let w = clamp(1.0 - x * x * x * x, 0.0, 1.0);
        f *= w * w;
    }
    return f;
}
