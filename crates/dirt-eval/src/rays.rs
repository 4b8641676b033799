//! Rays for a scene, deterministic for a seed, drawn from a tiny PCG32 so the
//! stream never changes under a dependency update.
//!
//! Two generators:
//!
//! * [`generate`]: test rays (`dirt rays`, `dirt bench`). The mixed set cycles
//!   through the adversarial families below, so any prefix of `count` rays
//!   already holds all of them.
//! * [`table1`]: the ray types of 001 Table 1 — primary, shadow, specular,
//!   glossy, diffuse — made at the primary hits of the scene's camera.
//!
//! Every ray passes [`Ray::validate`].

use dirt_math::{Aabb, Hit, Ray, Triangle, Vec3};
use dirt_scene::{CameraKind, Scene};

use crate::EvalError;

/// PCG32 (O'Neill, `pcg32_random_r` / XSH-RR), 64-bit state and stream.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    const MULT: u64 = 6_364_136_223_846_793_005;

    /// Same seeding as `pcg32_srandom_r(seed, stream)`.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in `[0, 1)` with 24 random bits.
    pub fn unit(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform integer in `[0, n)` (`n > 0`), multiply-shift.
    pub fn below(&mut self, n: usize) -> usize {
        ((u64::from(self.next_u32()) * n as u64) >> 32) as usize
    }

    pub fn coin(&mut self) -> bool {
        self.next_u32() & 1 == 1
    }

    /// Uniform on the unit sphere.
    pub fn sphere(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    pub fn in_box(&mut self, b: &Aabb) -> Vec3 {
        Vec3::new(
            self.range(b.min.x, b.max.x),
            self.range(b.min.y, b.max.y),
            self.range(b.min.z, b.max.z),
        )
    }

    /// Uniform barycentric point of a triangle.
    pub fn on_triangle(&mut self, t: &Triangle) -> Vec3 {
        let (mut a, mut b) = (self.unit(), self.unit());
        if a + b > 1.0 {
            (a, b) = (1.0 - a, 1.0 - b);
        }
        t.vertex(0) + a * (t.vertex(1) - t.vertex(0)) + b * (t.vertex(2) - t.vertex(0))
    }
}

/// Which test rays [`generate`] makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum RayKind {
    /// All families below, interleaved (the default; use it for exactness checks).
    Mixed,
    /// Primary rays of a pinhole camera outside the scene looking at its centre.
    Camera,
    /// Origins inside and outside the bounds towards random points in them.
    Random,
    /// Origins inside the bounds and on surfaces, in random directions.
    Inside,
}

/// The families of the mixed set, in the order they are cycled through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Family {
    OutsideToPoint,
    InsideToPoint,
    AxisAligned,
    AtVertex,
    AtEdgeMidpoint,
    Grazing,
    Segment,
    FromSurface,
    Camera,
}

const MIXED: [Family; 9] = [
    Family::OutsideToPoint,
    Family::InsideToPoint,
    Family::AxisAligned,
    Family::AtVertex,
    Family::AtEdgeMidpoint,
    Family::Grazing,
    Family::Segment,
    Family::FromSurface,
    Family::Camera,
];

/// What the generator knows about the scene.
struct Setting<'a> {
    tris: &'a [Triangle],
    /// Scene bounds, made at least a little thick in every axis.
    inner: Aabb,
    /// The bounds grown by half the diagonal on every side.
    outer: Aabb,
    diag: f32,
    camera: Camera,
}

/// The camera of the camera rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit right vector, orthogonal to `forward`.
    pub right: Vec3,
    /// Unit up vector, orthogonal to both.
    pub up: Vec3,
    /// Tangent of half the vertical field of view (perspective cameras).
    pub tan_half_fov: f32,
    /// Width / height of the image.
    pub aspect: f32,
    /// Half-width and half-height of the view volume of an orthographic camera.
    pub ortho: Option<(f32, f32)>,
}

impl Camera {
    /// A perspective camera; `forward` and `up` need not be unit or orthogonal.
    pub fn perspective(
        eye: Vec3,
        forward: Vec3,
        up: Vec3,
        yfov_radians: f32,
        aspect: f32,
    ) -> Option<Camera> {
        let forward = forward.try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        let tan_half_fov = (0.5 * yfov_radians).tan();
        let ok = eye.is_finite()
            && tan_half_fov.is_finite()
            && tan_half_fov > 0.0
            && aspect.is_finite()
            && aspect > 0.0;
        ok.then_some(Camera {
            eye,
            forward,
            right,
            up,
            tan_half_fov,
            aspect,
            ortho: None,
        })
    }

    /// An orthographic camera with half extents `xmag`, `ymag`.
    pub fn orthographic(
        eye: Vec3,
        forward: Vec3,
        up: Vec3,
        xmag: f32,
        ymag: f32,
    ) -> Option<Camera> {
        let mut cam = Camera::perspective(eye, forward, up, 1.0, 1.0)?;
        let ok = xmag.is_finite() && ymag.is_finite() && xmag != 0.0 && ymag != 0.0;
        cam.ortho = Some((xmag.abs(), ymag.abs()));
        cam.aspect = xmag.abs() / ymag.abs();
        ok.then_some(cam)
    }

    /// The scene's first camera, if it has one that makes sense.
    pub fn of_scene(scene: &Scene) -> Option<Camera> {
        let cam = scene.cameras.first()?;
        match cam.kind {
            CameraKind::Perspective => Camera::perspective(
                cam.position,
                cam.forward,
                cam.up,
                cam.yfov_radians,
                cam.aspect.unwrap_or(4.0 / 3.0),
            ),
            CameraKind::Orthographic { xmag, ymag } => {
                Camera::orthographic(cam.position, cam.forward, cam.up, xmag, ymag)
            }
        }
    }

    /// From the front (+z), a little above and to the side, far enough for the
    /// bounding sphere to fill the vertical field of view.
    pub fn in_front_of(bounds: &Aabb, diag: f32) -> Camera {
        let forward = Vec3::new(-0.15, -0.1, -1.0).normalize();
        let half_fov = 20f32.to_radians();
        let eye = bounds.center() - forward * (0.5 * diag / half_fov.sin());
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        Camera {
            eye,
            forward,
            right,
            up,
            tan_half_fov: half_fov.tan(),
            aspect: 4.0 / 3.0,
            ortho: None,
        }
    }

    /// The ray through pixel `(px, py)` of a `w × h` image, jittered inside the pixel.
    fn ray(&self, px: usize, py: usize, w: usize, h: usize, rng: &mut Pcg32) -> Ray {
        let sx = ((px as f32 + rng.unit()) / w as f32) * 2.0 - 1.0;
        let sy = 1.0 - ((py as f32 + rng.unit()) / h as f32) * 2.0;
        match self.ortho {
            Some((xmag, ymag)) => {
                let o = self.eye + self.right * (sx * xmag) + self.up * (sy * ymag);
                Ray::new(o, self.forward, 0.0, f32::INFINITY)
            }
            None => {
                let dir = self.forward
                    + self.right * (sx * self.tan_half_fov * self.aspect)
                    + self.up * (sy * self.tan_half_fov);
                Ray::new(self.eye, dir, 0.0, f32::INFINITY)
            }
        }
    }
}

/// `count` rays of `kind` for `tris`, deterministic for `seed`.
///
/// `camera` is used by the camera rays (`None`: one in front of the scene).
/// Returns an error only for an empty or non-finite scene.
pub fn generate(
    tris: &[Triangle],
    camera: Option<Camera>,
    kind: RayKind,
    count: usize,
    seed: u64,
) -> Result<Vec<Ray>, EvalError> {
    let bounds = checked_bounds(tris)?;
    let diag = bounds.extent().length().max(1e-3);
    let thick = Vec3::splat(1e-3 * diag);
    let inner = Aabb {
        min: bounds.min - thick,
        max: bounds.max + thick,
    };
    let outer = Aabb {
        min: bounds.min - Vec3::splat(0.5 * diag),
        max: bounds.max + Vec3::splat(0.5 * diag),
    };
    let s = Setting {
        tris,
        inner,
        outer,
        diag,
        camera: camera.unwrap_or_else(|| Camera::in_front_of(&bounds, diag)),
    };

    let mut rng = Pcg32::new(seed, 0xd1b5_4a32_d192_ed03);
    let mut rays = Vec::with_capacity(count);
    // Camera rays cover an image whose pixel count is at least `count` (or at
    // least the share of them in the mixed set), scanned in a scrambled order.
    let camera_rays = match kind {
        RayKind::Camera => count,
        RayKind::Mixed => count.div_ceil(MIXED.len()),
        _ => 0,
    };
    let (w, h) = image_size(camera_rays, s.camera.aspect);
    let mut camera_index = 0usize;
    for i in 0..count {
        let family = match kind {
            RayKind::Mixed => MIXED[i % MIXED.len()],
            RayKind::Camera => Family::Camera,
            RayKind::Random => {
                if rng.coin() {
                    Family::OutsideToPoint
                } else {
                    Family::InsideToPoint
                }
            }
            RayKind::Inside => {
                if rng.coin() {
                    Family::InsideToPoint
                } else {
                    Family::FromSurface
                }
            }
        };
        let ray = loop {
            let ray = match family {
                Family::Camera => {
                    // Scramble the scan with a multiplier coprime to the pixel count.
                    let n = w * h;
                    let p = (camera_index.wrapping_mul(coprime_stride(n))) % n;
                    s.camera.ray(p % w, p / w, w, h, &mut rng)
                }
                f => s.ray(f, kind, &mut rng),
            };
            if ray.validate().is_ok() {
                break ray;
            }
        };
        if family == Family::Camera {
            camera_index += 1;
        }
        rays.push(ray);
    }
    Ok(rays)
}

/// An image of about the given aspect with at least `n` pixels.
fn image_size(n: usize, aspect: f32) -> (usize, usize) {
    let n = n.max(1);
    let aspect = f64::from(aspect).clamp(0.01, 100.0);
    let h = ((n as f64 / aspect).sqrt().ceil() as usize).clamp(1, n);
    let w = n.div_ceil(h).max(1);
    (w, h)
}

fn coprime_stride(n: usize) -> usize {
    // A large odd stride near n·(golden ratio − 1) that shares no factor with n.
    let mut s = ((n as f64 * 0.618_034) as usize) | 1;
    while gcd(s, n) != 1 {
        s += 2;
    }
    s
}

fn gcd(mut a: usize, mut b: usize) -> usize {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

impl Setting<'_> {
    fn triangle(&self, rng: &mut Pcg32) -> &Triangle {
        &self.tris[rng.below(self.tris.len())]
    }

    /// A point of the outer box that is outside the scene bounds.
    fn outside(&self, rng: &mut Pcg32) -> Vec3 {
        loop {
            let p = rng.in_box(&self.outer);
            let inside = p.cmpge(self.inner.min).all() && p.cmple(self.inner.max).all();
            if !inside {
                return p;
            }
        }
    }

    /// An origin inside or outside the bounds (half and half).
    fn anywhere(&self, rng: &mut Pcg32) -> Vec3 {
        if rng.coin() {
            self.outside(rng)
        } else {
            rng.in_box(&self.inner)
        }
    }

    /// Scales a direction: unit length, its natural length, or something odd,
    /// so that `t` is not always a distance.
    fn scaled(&self, d: Vec3, rng: &mut Pcg32) -> Vec3 {
        match rng.below(4) {
            0 => d.normalize_or_zero(),
            1 => d * rng.range(0.01, 100.0),
            _ => d,
        }
    }

    fn ray(&self, family: Family, kind: RayKind, rng: &mut Pcg32) -> Ray {
        let unbounded = f32::INFINITY;
        match family {
            Family::OutsideToPoint => {
                let o = self.outside(rng);
                let target = if kind == RayKind::Mixed && rng.coin() {
                    let t = self.triangle(rng);
                    rng.on_triangle(t)
                } else {
                    rng.in_box(&self.inner)
                };
                Ray::new(o, self.scaled(target - o, rng), 0.0, unbounded)
            }
            Family::InsideToPoint => {
                let o = rng.in_box(&self.inner);
                let d = if rng.coin() {
                    rng.in_box(&self.inner) - o
                } else {
                    rng.sphere()
                };
                Ray::new(o, self.scaled(d, rng), 0.0, unbounded)
            }
            Family::AxisAligned => {
                let o = if rng.below(4) == 0 {
                    // Through a vertex coordinate, so the ray runs along a wall or an edge.
                    let t = self.triangle(rng);
                    let v = t.vertex(rng.below(3));
                    let mut o = rng.in_box(&self.outer);
                    let keep = rng.below(3);
                    for axis in 0..3 {
                        if axis != keep {
                            o[axis] = v[axis];
                        }
                    }
                    o
                } else {
                    self.anywhere(rng)
                };
                let axis = rng.below(3);
                let mut d = Vec3::ZERO;
                d[axis] = if rng.coin() { 1.0 } else { -1.0 }
                    * if rng.coin() {
                        1.0
                    } else {
                        rng.range(0.1, 10.0)
                    };
                Ray::new(o, d, 0.0, unbounded)
            }
            Family::AtVertex => {
                let t = self.triangle(rng);
                let v = t.vertex(rng.below(3));
                let o = self.anywhere(rng);
                let (tmin, tmax) = if rng.below(4) == 0 {
                    (0.0, 1.0)
                } else {
                    (0.0, unbounded)
                };
                // dir = v − o exactly (up to rounding): the ray is aimed at the vertex,
                // and with tmax = 1 it ends on it.
                Ray::new(o, v - o, tmin, tmax)
            }
            Family::AtEdgeMidpoint => {
                let t = self.triangle(rng);
                let i = rng.below(3);
                let m = 0.5 * (t.vertex(i) + t.vertex((i + 1) % 3));
                let o = self.anywhere(rng);
                Ray::new(o, self.scaled(m - o, rng), 0.0, unbounded)
            }
            Family::Grazing => {
                let t = self.triangle(rng);
                let (a, b, c) = (t.vertex(0), t.vertex(1), t.vertex(2));
                let (p, d) = match rng.below(3) {
                    // Along an edge line.
                    0 => {
                        let i = rng.below(3);
                        let (p, q) = (t.vertex(i), t.vertex((i + 1) % 3));
                        (p, q - p)
                    }
                    // In the plane through an interior point.
                    1 => {
                        let d = (b - a) * rng.range(-1.0, 1.0) + (c - a) * rng.range(-1.0, 1.0);
                        (rng.on_triangle(t), d)
                    }
                    // In the plane through a vertex.
                    _ => {
                        let d = (b - a) * rng.range(-1.0, 1.0) + (c - a) * rng.range(-1.0, 1.0);
                        (t.vertex(rng.below(3)), d)
                    }
                };
                let d = if d.length_squared() > 0.0 {
                    d
                } else {
                    rng.sphere()
                };
                // Start before the point, in the plane.
                let o = p - d.normalize_or_zero() * rng.range(0.05, 1.0) * self.diag;
                Ray::new(o, self.scaled(d, rng), 0.0, unbounded)
            }
            Family::Segment => {
                let o = self.anywhere(rng);
                let target = rng.in_box(&self.inner);
                let d = target - o;
                let tmin = if rng.coin() { 0.0 } else { rng.range(0.0, 0.5) };
                let tmax = match rng.below(3) {
                    0 => tmin,
                    1 => 1.0,
                    _ => rng.range(tmin, 1.5),
                };
                Ray::new(o, d, tmin, tmax.max(tmin))
            }
            Family::FromSurface => {
                // A bounce: from a point on a triangle, with a small tmin (or none).
                let t = self.triangle(rng);
                let o = rng.on_triangle(t);
                let tmin = match rng.below(3) {
                    0 => 0.0,
                    1 => 1e-4 * self.diag,
                    _ => 1e-6 * self.diag,
                };
                let d = rng.sphere();
                Ray::new(
                    o,
                    d,
                    tmin,
                    if rng.below(4) == 0 {
                        0.25 * self.diag
                    } else {
                        unbounded
                    },
                )
            }
            Family::Camera => unreachable!("camera rays are made by the caller"),
        }
    }
}

/// The scene bounds, or an error for an empty or non-finite scene.
fn checked_bounds(tris: &[Triangle]) -> Result<Aabb, EvalError> {
    if tris.is_empty() {
        return Err(EvalError::Rays(
            "the scene has no triangles to aim at".into(),
        ));
    }
    let bounds = Aabb::of_triangles(tris);
    if !(bounds.min.is_finite() && bounds.max.is_finite()) {
        return Err(EvalError::Rays("the scene has non-finite vertices".into()));
    }
    Ok(bounds)
}

/// The ray types of 001 Table 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RayType {
    /// Camera rays through jittered pixels.
    Primary,
    /// Visibility: from a primary hit to a point on an emitter (or a point
    /// light), ending just short of it.
    Shadow,
    /// Mirror reflection at a primary hit.
    Specular,
    /// Mirror reflection perturbed by a Phong lobe (exponent [`GLOSSY_EXPONENT`]).
    Glossy,
    /// Cosine-weighted hemisphere at a primary hit.
    Diffuse,
}

impl RayType {
    pub const ALL: [RayType; 5] = [
        RayType::Primary,
        RayType::Shadow,
        RayType::Specular,
        RayType::Glossy,
        RayType::Diffuse,
    ];

    pub fn name(self) -> &'static str {
        match self {
            RayType::Primary => "primary",
            RayType::Shadow => "shadow",
            RayType::Specular => "specular",
            RayType::Glossy => "glossy",
            RayType::Diffuse => "diffuse",
        }
    }
}

impl std::fmt::Display for RayType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Phong exponent of the glossy lobe.
pub const GLOSSY_EXPONENT: f32 = 64.0;

/// Where shadow rays end: points on emissive triangles (area-weighted), else
/// the scene's punctual lights, else one point above the scene.
#[derive(Clone, Debug)]
enum Emitters {
    Triangles { tris: Vec<Triangle>, cdf: Vec<f32> },
    Points(Vec<Vec3>),
}

impl Emitters {
    fn of_scene(scene: &Scene, bounds: &Aabb, diag: f32) -> Emitters {
        let tris: Vec<Triangle> = scene
            .triangles
            .iter()
            .enumerate()
            .filter(|(i, _)| scene.material_of(*i).is_some_and(|m| m.is_emissive()))
            .map(|(_, t)| *t)
            .collect();
        if !tris.is_empty() {
            let mut acc = 0.0f32;
            let cdf = tris
                .iter()
                .map(|t| {
                    let e = (t.vertex(1) - t.vertex(0)).cross(t.vertex(2) - t.vertex(0));
                    acc += 0.5 * e.length();
                    acc
                })
                .collect();
            return Emitters::Triangles { tris, cdf };
        }
        let points: Vec<Vec3> = scene
            .lights
            .iter()
            .filter(|l| !matches!(l.kind, dirt_scene::LightKind::Directional))
            .map(|l| l.position)
            .filter(|p| p.is_finite())
            .collect();
        if !points.is_empty() {
            return Emitters::Points(points);
        }
        let c = bounds.center();
        Emitters::Points(vec![Vec3::new(c.x, bounds.max.y + 0.25 * diag, c.z)])
    }

    fn sample(&self, rng: &mut Pcg32) -> Vec3 {
        match self {
            Emitters::Triangles { tris, cdf } => {
                let total = cdf.last().copied().unwrap_or(0.0);
                let x = rng.unit() * total;
                let i = cdf.partition_point(|&c| c <= x).min(tris.len() - 1);
                rng.on_triangle(&tris[i])
            }
            Emitters::Points(p) => p[rng.below(p.len())],
        }
    }
}

/// A unit vector around unit `axis`: `cos θ = u^(1/(e+1))` (Phong lobe of
/// exponent `e`; `e = 1` with the cosine around a normal is the diffuse lobe).
fn lobe(axis: Vec3, exponent: f32, rng: &mut Pcg32) -> Vec3 {
    let cos_t = rng.unit().powf(1.0 / (exponent + 1.0));
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = rng.range(0.0, std::f32::consts::TAU);
    let helper = if axis.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let t = axis.cross(helper).normalize();
    let b = axis.cross(t);
    (t * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + axis * cos_t).normalize()
}

/// A cosine-weighted direction around unit `n` (Malley's method).
fn cosine_hemisphere(n: Vec3, rng: &mut Pcg32) -> Vec3 {
    let r = rng.unit().sqrt();
    let phi = rng.range(0.0, std::f32::consts::TAU);
    let z = (1.0 - r * r).max(0.0).sqrt();
    let helper = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let t = n.cross(helper).normalize();
    let b = n.cross(t);
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * z).normalize()
}

/// Rays of every type of 001 Table 1, `count` of each, deterministic for `seed`.
///
/// Primary rays come from [`primary_camera`]. Secondary rays start at primary hits, found with `closest` (any
/// exact tracer), cycling through the hits in order; they start a small
/// offset (`1e-4` of the scene diagonal) off the surface along its geometric
/// normal, facing the incoming ray. Fails when no primary ray hits anything.
/// The camera of [`table1`]'s primary rays: the scene's first camera, else
/// one in front of the scene.
pub fn primary_camera(scene: &Scene) -> Result<Camera, EvalError> {
    let bounds = checked_bounds(&scene.triangles)?;
    let diag = bounds.extent().length().max(1e-3);
    Ok(Camera::of_scene(scene).unwrap_or_else(|| Camera::in_front_of(&bounds, diag)))
}

pub fn table1(
    scene: &Scene,
    count: usize,
    seed: u64,
    closest: impl Fn(&[Ray]) -> Vec<Hit>,
) -> Result<Vec<(RayType, Vec<Ray>)>, EvalError> {
    let tris = &scene.triangles;
    let bounds = checked_bounds(tris)?;
    let diag = bounds.extent().length().max(1e-3);
    let camera = primary_camera(scene)?;
    let primary = generate(tris, Some(camera), RayKind::Camera, count, seed)?;
    let hits = closest(&primary);
    let points: Vec<(Vec3, Vec3, Vec3)> = primary
        .iter()
        .zip(&hits)
        .filter(|(_, h)| h.is_hit() && (h.prim as usize) < tris.len())
        .filter_map(|(r, h)| {
            let t = &tris[h.prim as usize];
            let d = r.dir().normalize_or_zero();
            let n = (t.vertex(1) - t.vertex(0))
                .cross(t.vertex(2) - t.vertex(0))
                .normalize_or_zero();
            let n = if n.dot(d) > 0.0 { -n } else { n };
            let p = r.origin() + r.dir() * h.t;
            (p.is_finite() && n != Vec3::ZERO && d != Vec3::ZERO).then_some((p, n, d))
        })
        .collect();
    if points.is_empty() && count > 0 {
        return Err(EvalError::Rays(format!(
            "no primary ray of scene {} hits anything; no secondary rays can be made",
            scene.name
        )));
    }
    let emitters = Emitters::of_scene(scene, &bounds, diag);
    let offset = 1e-4 * diag;
    let mut out = vec![(RayType::Primary, primary)];
    for (k, ty) in RayType::ALL.into_iter().enumerate().skip(1) {
        let mut rng = Pcg32::new(seed, 0x7ab1e1 + k as u64);
        let mut rays = Vec::with_capacity(count);
        let mut i = 0usize;
        while rays.len() < count {
            let (p, n, d) = points[i % points.len()];
            i += 1;
            let o = p + n * offset;
            let ray = match ty {
                RayType::Shadow => {
                    let l = emitters.sample(&mut rng);
                    // Ends just short of the emitter, so the emitter itself is no occluder.
                    Ray::new(o, l - o, 0.0, 1.0 - 1e-4)
                }
                RayType::Specular => Ray::new(o, d - n * (2.0 * d.dot(n)), 0.0, f32::INFINITY),
                RayType::Glossy => {
                    let r = (d - n * (2.0 * d.dot(n))).normalize_or_zero();
                    let mut g = lobe(r, GLOSSY_EXPONENT, &mut rng);
                    if g.dot(n) <= 0.0 {
                        // Below the surface: mirror the sample about the tangent plane.
                        g -= n * (2.0 * g.dot(n));
                    }
                    Ray::new(o, g, 0.0, f32::INFINITY)
                }
                RayType::Diffuse => Ray::new(o, cosine_hemisphere(n, &mut rng), 0.0, f32::INFINITY),
                RayType::Primary => unreachable!("primary rays are made above"),
            };
            if ray.validate().is_ok() {
                rays.push(ray);
            } else if i > 4 * count + points.len() {
                return Err(EvalError::Rays(format!(
                    "could not make valid {ty} rays for scene {}",
                    scene.name
                )));
            }
        }
        out.push((ty, rays));
    }
    Ok(out)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn pcg32_matches_the_reference_stream() {
        // pcg32-demo, seed 42 stream 54 (pcg-c-basic).
        let mut rng = Pcg32::new(42, 54);
        let got: Vec<u32> = (0..6).map(|_| rng.next_u32()).collect();
        assert_eq!(
            got,
            [
                0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e
            ]
        );
    }

    #[test]
    fn unit_and_below_stay_in_range() {
        let mut rng = Pcg32::new(1, 2);
        for _ in 0..10_000 {
            let u = rng.unit();
            assert!((0.0..1.0).contains(&u));
            assert!(rng.below(7) < 7);
        }
    }

    fn quad() -> Vec<Triangle> {
        let (a, b, c, d) = (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
        vec![
            Triangle::new(a, b, c),
            Triangle::new(a, c, d),
            Triangle::new(a, b, Vec3::Z),
        ]
    }

    #[test]
    fn every_kind_is_valid_deterministic_and_sized() {
        let tris = quad();
        for kind in [
            RayKind::Mixed,
            RayKind::Camera,
            RayKind::Random,
            RayKind::Inside,
        ] {
            let a = generate(&tris, None, kind, 1000, 7).expect("rays");
            let b = generate(&tris, None, kind, 1000, 7).expect("rays");
            let c = generate(&tris, None, kind, 1000, 8).expect("rays");
            assert_eq!(a.len(), 1000);
            assert!(a.iter().all(|r| r.validate().is_ok()), "{kind:?}");
            assert_eq!(
                bytemuck::cast_slice::<Ray, u8>(&a),
                bytemuck::cast_slice::<Ray, u8>(&b),
                "{kind:?}"
            );
            assert_ne!(
                bytemuck::cast_slice::<Ray, u8>(&a),
                bytemuck::cast_slice::<Ray, u8>(&c),
                "{kind:?}"
            );
        }
    }

    #[test]
    fn mixed_holds_the_adversarial_families() {
        let tris = quad();
        let rays = generate(&tris, None, RayKind::Mixed, 900, 3).expect("rays");
        let axis_aligned = rays
            .iter()
            .filter(|r| r.dir.iter().filter(|&&c| c == 0.0).count() == 2)
            .count();
        let limited = rays.iter().filter(|r| r.tmax.is_finite()).count();
        let with_tmin = rays.iter().filter(|r| r.tmin > 0.0).count();
        assert!(axis_aligned >= 100, "{axis_aligned}");
        assert!(limited >= 100, "{limited}");
        assert!(with_tmin >= 50, "{with_tmin}");
    }

    #[test]
    fn an_empty_scene_is_an_error() {
        assert!(generate(&[], None, RayKind::Mixed, 10, 0).is_err());
    }

    #[test]
    fn table1_rays_are_valid_deterministic_and_typed() {
        let scene = dirt_scene::builtin("cornell").expect("cornell");
        let closest = |r: &[Ray]| dirt_cpu::brute_force::trace(&scene.triangles, r);
        let a = table1(&scene, 200, 5, closest).expect("rays");
        let b = table1(&scene, 200, 5, closest).expect("rays");
        assert_eq!(a.len(), 5);
        for ((ta, ra), (tb, rb)) in a.iter().zip(&b) {
            assert_eq!(ta, tb);
            assert_eq!(ra.len(), 200, "{ta}");
            assert!(ra.iter().all(|r| r.validate().is_ok()), "{ta}");
            assert_eq!(
                bytemuck::cast_slice::<Ray, u8>(ra),
                bytemuck::cast_slice::<Ray, u8>(rb)
            );
        }
        let of = |t: RayType| &a.iter().find(|(x, _)| *x == t).expect("type").1;
        // Shadow rays are segments; the others are unbounded.
        assert!(of(RayType::Shadow).iter().all(|r| r.tmax < 1.0));
        assert!(of(RayType::Diffuse).iter().all(|r| r.tmax.is_infinite()));
        // Secondary rays start where primary rays hit: inside the room.
        let bounds = scene.bounds();
        for t in [RayType::Specular, RayType::Glossy, RayType::Diffuse] {
            assert!(of(t).iter().all(|r| {
                let o = r.origin();
                o.cmpge(bounds.min - 0.01).all() && o.cmple(bounds.max + 0.01).all()
            }));
        }
        // Cornell has an emissive ceiling: most shadow rays end near its height.
        let ends_high = of(RayType::Shadow)
            .iter()
            .filter(|r| (r.origin() + r.dir()).y > bounds.max.y - 0.1 * bounds.extent().y)
            .count();
        assert!(ends_high > 150, "{ends_high}");
    }

    #[test]
    fn a_scene_nothing_hits_is_an_error() {
        let scene = dirt_scene::builtin("cornell").expect("cornell");
        let err = table1(&scene, 10, 1, |r: &[Ray]| vec![Hit::MISS; r.len()]).expect_err("no hits");
        assert!(err.to_string().contains("hits anything"), "{err}");
    }

    #[test]
    fn image_size_covers_the_count() {
        for n in [0, 1, 2, 3, 7, 100, 1000, 12345] {
            for aspect in [1.0, 4.0 / 3.0, 0.2, 50.0] {
                let (w, h) = image_size(n, aspect);
                assert!(w * h >= n.max(1), "{n}: {w}x{h}");
            }
        }
    }
}
