// Stage `fetch` of the GPU renderer (dirt_render::fetch): the surface point
// of every hit — barycentric position, geometric and shading normal on the
// side the ray came from, texture coordinates, the base-colour texture
// (bilinear, repeat; decoded to linear on the host, as on the CPU) and the
// material — only for primitives that were hit.

#import render_types

@group(0) @binding(0) var<uniform> params: RenderParams;
@group(0) @binding(1) var<storage, read_write> state: RenderState;
@group(0) @binding(2) var<storage, read> rays: array<Ray>;
@group(0) @binding(3) var<storage, read> hits: array<Hit>;
@group(0) @binding(4) var<storage, read> tris: array<TriGpu>;
@group(0) @binding(5) var<storage, read> materials: array<MaterialGpu>;
@group(0) @binding(6) var<storage, read> textures: array<TextureGpu>;
@group(0) @binding(7) var<storage, read> texels: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> surfaces: array<SurfaceGpu>;

fn no_surface() -> SurfaceGpu {
    return SurfaceGpu(vec3<f32>(0.0), NO_PRIM, vec3<f32>(0.0), 0u, vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0u);
}

fn texel(t: TextureGpu, x: i32, y: i32) -> vec4<f32> {
    let w = i32(t.width);
    let h = i32(t.height);
    let xi = ((x % w) + w) % w;
    let yi = ((y % h) + h) % h;
    return texels[t.offset + u32(yi * w + xi)];
}

// LinearTexture::sample: bilinear with repeat wrapping, (0, 0) the top-left corner.
fn texture_sample(t: TextureGpu, uv: vec2<f32>) -> vec4<f32> {
    if (t.width == 0u) | (t.height == 0u) | !(finite1(uv.x) & finite1(uv.y)) {
        return vec4<f32>(1.0);
    }
    let x = uv.x * f32(t.width) - 0.5;
    let y = uv.y * f32(t.height) - 0.5;
    let x0f = floor(x);
    let y0f = floor(y);
    let fx = x - x0f;
    let fy = y - y0f;
    let x0 = i32(x0f);
    let y0 = i32(y0f);
    let a = mix(texel(t, x0, y0), texel(t, x0 + 1, y0), fx);
    let b = mix(texel(t, x0, y0 + 1), texel(t, x0 + 1, y0 + 1), fx);
    return mix(a, b, fy);
}

@compute @workgroup_size(64)
fn fetch(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = path_index(gid, groups);
    if i >= params.n_paths {
        return;
    }
    let hit = hits[i];
    if hit_unfinished(hit) {
        atomicAdd(&state.bad_hits, 1u);
    }
    if hit.prim >= params.n_tris {
        surfaces[i] = no_surface();
        return;
    }
    let tri = tris[hit.prim];
    if tri.material >= params.n_materials {
        surfaces[i] = no_surface();
        return;
    }
    let ray = rays[i];
    let u = hit.u;
    let v = hit.v;
    let w = 1.0 - u - v;
    let p = tri.p0 * w + tri.p1 * u + tri.p2 * v;
    let face = normalize_or_zero(cross(tri.p1 - tri.p0, tri.p2 - tri.p0));
    let front = dot3(face, ray.dir) < 0.0;
    let ng = select(-face, face, front);
    var ns = ng;
    if tri.has_normals != 0u {
        ns = normalize_or_zero(tri.n0 * w + tri.n1 * u + tri.n2 * v);
        if all(ns == vec3<f32>(0.0)) {
            ns = ng;
        }
    }
    if dot3(ns, ng) < 0.0 {
        ns = -ns;
    }
    var uv = vec2<f32>(0.0);
    if tri.has_uvs != 0u {
        uv = tri.uv0 * w + tri.uv1 * u + tri.uv2 * v;
    }
    let m = materials[tri.material];
    var base = m.base;
    if m.texture < arrayLength(&textures) {
        base *= texture_sample(textures[m.texture], uv).xyz;
    }
    let emission = select(vec3<f32>(0.0), m.emissive, front);
    surfaces[i] = SurfaceGpu(
        p, hit.prim, ng, u32(front), ns, clamp(m.metallic, 0.0, 1.0),
        clamp(base, vec3<f32>(0.0), vec3<f32>(1.0)), clamp(m.roughness, 0.0, 1.0), emission, 0u,
    );
}
