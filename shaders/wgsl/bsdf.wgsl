// Mirrors dirt_render::bsdf: the metallic-roughness BSDF of glTF as a
// Lambertian, a perfect mirror, or a diffuse plus GGX specular pair. Same
// formulas, same order; sqrt, sin, cos and division are the GPU's, so values
// agree with the CPU's to rounding, not to the bit.

#import render_types

const PI_F: f32 = 3.14159274;
const MIRROR_ROUGHNESS: f32 = 0.02;
const BSDF_LAMBERT: u32 = 0u;
const BSDF_MIRROR: u32 = 1u;
const BSDF_MICROFACET: u32 = 2u;

struct Bsdf {
    kind: u32,
    // Lambert: the albedo; microfacet: the diffuse colour.
    colour: vec3<f32>,
    f0: vec3<f32>,
    alpha: f32,
    p_spec: f32,
}

struct BsdfSample {
    ok: bool,
    wi: vec3<f32>,
    weight: vec3<f32>,
    pdf: f32,
    delta: bool,
}

fn no_bsdf_sample() -> BsdfSample {
    return BsdfSample(false, vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false);
}

// Duff et al. 2017.
fn basis_t(n: vec3<f32>) -> vec3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
}

fn basis_b(n: vec3<f32>) -> vec3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(b, sign + n.y * n.y * a, -n.y);
}

fn cosine_sample(n: vec3<f32>, u1: f32, u2: f32) -> vec3<f32> {
    let t = basis_t(n);
    let b = basis_b(n);
    let r = sqrt(u1);
    let phi = 2.0 * PI_F * u2;
    return normalize_glam(t * (r * cos(phi)) + b * (r * sin(phi)) + n * sqrt(max(1.0 - u1, 0.0)));
}

fn schlick(f0: vec3<f32>, c: f32) -> vec3<f32> {
    let m = clamp(1.0 - c, 0.0, 1.0);
    let m5 = m * m * m * m * m;
    return f0 + (vec3<f32>(1.0) - f0) * m5;
}

fn ggx_d(alpha: f32, noh: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = noh * noh * (a2 - 1.0) + 1.0;
    return a2 / (PI_F * d * d);
}

fn smith_vis(alpha: f32, nov: f32, nol: f32) -> f32 {
    let a2 = alpha * alpha;
    let gv = nol * sqrt(nov * nov * (1.0 - a2) + a2);
    let gl = nov * sqrt(nol * nol * (1.0 - a2) + a2);
    let s = gv + gl;
    return select(0.0, 0.5 / s, s > 0.0);
}

fn bsdf_of(sp: SurfaceGpu) -> Bsdf {
    if (sp.metallic == 0.0) & (sp.roughness >= 1.0) {
        return Bsdf(BSDF_LAMBERT, sp.base, vec3<f32>(0.0), 0.0, 0.0);
    }
    let f0 = mix(vec3<f32>(0.04), sp.base, sp.metallic);
    if (sp.metallic >= 1.0) & (sp.roughness <= MIRROR_ROUGHNESS) {
        return Bsdf(BSDF_MIRROR, vec3<f32>(0.0), f0, 0.0, 0.0);
    }
    let alpha = max(sp.roughness * sp.roughness, 1e-3);
    return Bsdf(BSDF_MICROFACET, sp.base * (1.0 - sp.metallic), f0, alpha, 0.25 + 0.75 * sp.metallic);
}

fn bsdf_eval(f: Bsdf, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let nol = dot3(n, wi);
    let nov = dot3(n, wo);
    if (nol <= 0.0) | (nov <= 0.0) {
        return vec3<f32>(0.0);
    }
    if f.kind == BSDF_LAMBERT {
        return f.colour / PI_F;
    }
    if f.kind == BSDF_MIRROR {
        return vec3<f32>(0.0);
    }
    let h = normalize_or_zero(wo + wi);
    if all(h == vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    let voh = max(dot3(wo, h), 0.0);
    let fr = schlick(f.f0, voh);
    let spec = fr * (ggx_d(f.alpha, max(dot3(n, h), 0.0)) * smith_vis(f.alpha, nov, nol));
    let fd = schlick(vec3<f32>(0.04), voh);
    return f.colour * (vec3<f32>(1.0) - fd) / PI_F + spec;
}

fn bsdf_pdf(f: Bsdf, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    let nol = dot3(n, wi);
    if (nol <= 0.0) | (dot3(n, wo) <= 0.0) {
        return 0.0;
    }
    if f.kind == BSDF_LAMBERT {
        return nol / PI_F;
    }
    if f.kind == BSDF_MIRROR {
        return 0.0;
    }
    let h = normalize_or_zero(wo + wi);
    let voh = dot3(wo, h);
    var spec = 0.0;
    if voh > 0.0 {
        let noh = max(dot3(n, h), 0.0);
        spec = ggx_d(f.alpha, noh) * noh / (4.0 * voh);
    }
    return f.p_spec * spec + (1.0 - f.p_spec) * nol / PI_F;
}

fn bsdf_sample(f: Bsdf, n: vec3<f32>, ng: vec3<f32>, wo: vec3<f32>, u_lobe: f32, u1: f32, u2: f32) -> BsdfSample {
    if dot3(n, wo) <= 0.0 {
        return no_bsdf_sample();
    }
    var wi: vec3<f32>;
    if f.kind == BSDF_LAMBERT {
        wi = cosine_sample(n, u1, u2);
    } else if f.kind == BSDF_MIRROR {
        wi = normalize_glam(n * (2.0 * dot3(n, wo)) - wo);
    } else if u_lobe < f.p_spec {
        let t = basis_t(n);
        let b = basis_b(n);
        let phi = 2.0 * PI_F * u2;
        let cos2 = (1.0 - u1) / (1.0 + (f.alpha * f.alpha - 1.0) * u1);
        let c = sqrt(max(cos2, 0.0));
        let s = sqrt(max(1.0 - cos2, 0.0));
        let h = normalize_glam(t * (s * cos(phi)) + b * (s * sin(phi)) + n * c);
        wi = normalize_glam(h * (2.0 * dot3(h, wo)) - wo);
    } else {
        wi = cosine_sample(n, u1, u2);
    }
    if !((dot3(wi, ng) > 0.0) & (dot3(wi, n) > 0.0) & finite3(wi)) {
        return no_bsdf_sample();
    }
    var weight: vec3<f32>;
    var pdf = 0.0;
    var delta = false;
    if f.kind == BSDF_MIRROR {
        // f·cos/pdf is the Fresnel term.
        weight = schlick(f.f0, dot3(n, wo));
        delta = true;
    } else if f.kind == BSDF_LAMBERT {
        // f·cos/pdf = albedo exactly.
        weight = f.colour;
        pdf = dot3(n, wi) / PI_F;
    } else {
        pdf = bsdf_pdf(f, n, wo, wi);
        if !(pdf > 0.0) {
            return no_bsdf_sample();
        }
        weight = bsdf_eval(f, n, wo, wi) * (dot3(n, wi) / pdf);
    }
    if !finite3(weight) | all(weight == vec3<f32>(0.0)) {
        return no_bsdf_sample();
    }
    return BsdfSample(true, wi, weight, pdf, delta);
}
