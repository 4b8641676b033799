//! The GPU renderer's structs, declared once here; `render_types.wgsl`
//! declares their WGSL twins and `tests/tests/layout.rs` compares the two.

use bytemuck::{Pod, Zeroable};

/// No primitive: a surface that is not there, a texture that is not used,
/// a shadow ray aimed at no triangle.
pub const NO_PRIM: u32 = u32::MAX;

/// What every pass reads (a uniform, 128 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RenderParams {
    pub eye: [f32; 3],
    pub tan_half_fov: f32,
    pub forward: [f32; 3],
    pub ortho_half_height: f32,
    pub up: [f32; 3],
    pub orthographic: u32,
    pub right: [f32; 3],
    pub offset: f32,
    pub environment: [f32; 3],
    pub p_area: f32,
    /// `rng::seed_mix(seed)` as (low, high) words.
    pub seed_mix: [u32; 2],
    pub width: u32,
    pub height: u32,
    pub n_paths: u32,
    pub n_area: u32,
    pub n_punctual: u32,
    /// Russian roulette from this bounce on; `u32::MAX`: never.
    pub roulette_from: u32,
    pub n_tris: u32,
    pub n_materials: u32,
    /// `Mode::Ao`: the length of the occlusion rays ([`crate::Renderer::ao_radius`]).
    pub ao_radius: f32,
    pub pad1: u32,
}

impl RenderParams {
    /// The camera's fields: where the primary rays start and which way they go.
    pub fn set_camera(&mut self, c: &crate::Camera) {
        self.eye = c.eye.to_array();
        self.tan_half_fov = c.tan_half_fov;
        self.forward = c.forward.to_array();
        self.ortho_half_height = c.ortho_half_height.unwrap_or(0.0);
        self.up = c.up.to_array();
        self.orthographic = c.ortho_half_height.is_some() as u32;
        self.right = c.right.to_array();
    }
}

/// The sample and bounce being rendered (the host writes them before each
/// sample, `shift`'s `advance` moves the bounce on), hits that were not hits,
/// the valid rays traced and the primary rays whose rasterised candidate
/// `direct_visibility` confirmed: this sample's, added to 64-bit totals by
/// `shift`'s `tally`; the valid rays `shift`'s `compact` packed for the
/// trace being recorded (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct RenderState {
    pub sample: u32,
    pub bounce: u32,
    pub bad_hits: u32,
    pub rays: u32,
    pub rays_lo: u32,
    pub rays_hi: u32,
    pub confirmed: u32,
    pub confirmed_lo: u32,
    pub confirmed_hi: u32,
    pub live: u32,
}

impl RenderState {
    /// The valid rays traced, all samples so far (`tally`'s 64-bit total).
    pub fn rays_total(&self) -> u64 {
        u64::from(self.rays_lo) | (u64::from(self.rays_hi) << 32)
    }

    /// The primary rays whose candidate was confirmed, all samples so far.
    pub fn confirmed_total(&self) -> u64 {
        u64::from(self.confirmed_lo) | (u64::from(self.confirmed_hi) << 32)
    }
}

/// A triangle with what `fetch` and the lights read (128 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriGpu {
    pub p0: [f32; 3],
    /// `Lights::prim_prob` of the triangle.
    pub light_prob: f32,
    pub p1: [f32; 3],
    /// Index into the materials; `NO_PRIM` where `Scene::material_of` has none.
    pub material: u32,
    pub p2: [f32; 3],
    pub has_normals: u32,
    pub n0: [f32; 3],
    pub has_uvs: u32,
    pub n1: [f32; 3],
    pub pad0: u32,
    pub n2: [f32; 3],
    pub pad1: u32,
    pub uv0: [f32; 2],
    pub uv1: [f32; 2],
    pub uv2: [f32; 2],
    pub pad2: [f32; 2],
}

/// A material as shading reads it (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MaterialGpu {
    pub base: [f32; 3],
    pub metallic: f32,
    pub emissive: [f32; 3],
    pub roughness: f32,
    /// Index into the decoded textures; `NO_PRIM`: none.
    pub texture: u32,
    pub pad0: u32,
    pub pad1: u32,
    pub pad2: u32,
}

/// A decoded texture's place in the texel array (16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct TextureGpu {
    pub offset: u32,
    pub width: u32,
    pub height: u32,
    pub pad: u32,
}

/// An area light (`kind` 0) or a punctual one (1 point, 2 spot, 3
/// directional), 64 bytes. Area lights come first, in `Lights::area` order.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct LightGpu {
    pub position: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    /// 0: no range.
    pub range: f32,
    /// Area: emitted radiance; punctual: colour times intensity.
    pub color: [f32; 3],
    pub cos_inner: f32,
    pub cos_outer: f32,
    pub prim: u32,
    pub area: f32,
    pub cdf: f32,
}

/// One path of the shading buffer (80 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PathGpu {
    pub throughput: [f32; 3],
    pub alive: u32,
    pub radiance: [f32; 3],
    pub pdf: f32,
    /// G(k-1).
    pub prev: [f32; 3],
    pub delta: u32,
    pub weight: [f32; 3],
    pub scattered: u32,
    pub dir: [f32; 3],
    pub pad: u32,
}

/// A fetched surface point (80 bytes); `prim` `NO_PRIM`: none.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SurfaceGpu {
    pub p: [f32; 3],
    pub prim: u32,
    pub ng: [f32; 3],
    pub front: u32,
    pub ns: [f32; 3],
    pub metallic: f32,
    pub base: [f32; 3],
    pub roughness: f32,
    pub emission: [f32; 3],
    pub pad: u32,
}

/// A shadow ray's payload (16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ShadowGpu {
    pub contribution: [f32; 3],
    /// The emissive triangle aimed at, `NO_PRIM` for punctual lights,
    /// `NO_PRIM - 1` when the path sent no shadow ray.
    pub aim: u32,
}

/// How the `output` pass tone-maps the sums (`output.wgsl`'s `Tone`, a uniform).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Tone {
    pub width: u32,
    pub height: u32,
    /// 1 / samples (0 before the first).
    pub inv_samples: f32,
    /// 2^exposure.
    pub scale: f32,
}
