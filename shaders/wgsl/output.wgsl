// Stage `output` of the GPU renderer (dirt_render::output): the image drawn
// on a window's or a canvas's texture by one fullscreen triangle, texel for
// texel (the nearest texel where the target is larger than the image).
// Either the renderer's radiance sums are tone-mapped where they lie, as
// Image::to_srgb8 writes its bytes (`fs_sums_*`: nothing is read back), or
// an image uploaded as sRGB bytes is copied (`fs_bytes_*`). The `_plain`
// entries write the bytes as they are to a plain 8-bit target; the `_srgb`
// ones decode them for an sRGB target, which encodes them again.

struct Out {
    @builtin(position) pos: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

// One triangle covering the target: (-1,-1), (3,-1), (-1,3).
@vertex
fn vs(@builtin(vertex_index) i: u32) -> Out {
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    var o: Out;
    o.pos = vec4<f32>(p * 2.0 - 1.0, 0.0, 1.0);
    o.uv = vec2<f32>(p.x, 1.0 - p.y);
    return o;
}

// The image's pixel under `uv`, of an image `size` pixels wide and high.
fn pixel(uv: vec2<f32>, size: vec2<i32>) -> vec2<i32> {
    return clamp(vec2<i32>(floor(uv * vec2<f32>(size))), vec2<i32>(0), size - 1);
}

fn decode(c: vec3<f32>) -> vec4<f32> {
    let lo = c / 12.92;
    let hi = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return vec4<f32>(select(hi, lo, c <= vec3<f32>(0.04045)), 1.0);
}

// An uploaded image: sRGB bytes in an rgba8unorm texture.
@group(0) @binding(0) var bytes: texture_2d<f32>;

fn byte_texel(uv: vec2<f32>) -> vec3<f32> {
    return textureLoad(bytes, pixel(uv, vec2<i32>(textureDimensions(bytes))), 0).rgb;
}

@fragment
fn fs_bytes_plain(in: Out) -> @location(0) vec4<f32> {
    return vec4<f32>(byte_texel(in.uv), 1.0);
}

@fragment
fn fs_bytes_srgb(in: Out) -> @location(0) vec4<f32> {
    return decode(byte_texel(in.uv));
}

// The GPU renderer's radiance sums (GpuRenderer::sums: width·height vec4,
// rows top to bottom) and how to tone-map their mean.
struct Tone {
    width: u32,
    height: u32,
    inv_samples: f32,
    // 2^exposure
    scale: f32,
}

@group(0) @binding(1) var<storage, read> sums: array<vec4<f32>>;
@group(0) @binding(2) var<uniform> tone: Tone;

// Image::to_srgb8's curve and transfer function, term for term.
fn aces(x: f32) -> f32 {
    let y = max(x, 0.0);
    return clamp((y * (2.51 * y + 0.03)) / (y * (2.43 * y + 0.59) + 0.14), 0.0, 1.0);
}

fn linear_to_srgb(x: f32) -> f32 {
    if x <= 0.0031308 {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

// One channel as the byte to_srgb8 writes, over 255 (non-finite: 0, told by
// the exponent bits: WGSL has no isfinite, and a finite comparison with
// them may be folded away).
fn to_byte(c: f32) -> f32 {
    let v = select(0.0, c, (bitcast<u32>(c) & 0x7f800000u) != 0x7f800000u);
    return floor(clamp(linear_to_srgb(aces(v * tone.scale)) * 255.0 + 0.5, 0.0, 255.0)) / 255.0;
}

fn mean_texel(uv: vec2<f32>) -> vec3<f32> {
    let xy = pixel(uv, vec2<i32>(i32(tone.width), i32(tone.height)));
    let m = sums[u32(xy.y) * tone.width + u32(xy.x)].rgb * tone.inv_samples;
    return vec3<f32>(to_byte(m.r), to_byte(m.g), to_byte(m.b));
}

@fragment
fn fs_sums_plain(in: Out) -> @location(0) vec4<f32> {
    return vec4<f32>(mean_texel(in.uv), 1.0);
}

@fragment
fn fs_sums_srgb(in: Out) -> @location(0) vec4<f32> {
    return decode(mean_texel(in.uv));
}
