//! Deterministic procedural scenes.

use std::f32::consts::{PI, TAU};

use dirt_math::{Triangle, Vec3};
use glam::{Mat4, Quat};

use crate::builder::SceneBuilder;
use crate::{Camera, Light, LightKind, Material, Scene};

/// The scene [`open`](crate::open) callers should use when none is given.
pub const DEFAULT_SCENE: &str = "cornell";

/// Names accepted by [`builtin`] (and [`open`](crate::open)).
pub const BUILTIN_NAMES: &[&str] = &["cornell", "layers", "foliage", "spheres"];

/// A built-in procedural scene by name, or `None` for an unknown name.
///
/// All are generated deterministically (fixed-seed SplitMix64, identical on
/// every run), y is up,
/// and each has one camera (looking down -Z unless stated) and material 0 =
/// default as usual. Triangle counts and flattened order:
///
/// * `cornell` (**998** triangles, the [`DEFAULT_SCENE`]): a room closed on
///   all six sides, `x ∈ [-1, 1]`, `y ∈ [0, 2]`, `z ∈ [-1, 2]`, every wall
///   facing inwards, in the order floor, ceiling, back wall (`z = -1`), red
///   left wall (`x = -1`), green right wall (`x = 1`), front wall (`z = 2`)
///   (2 triangles each); an emissive quad just below the ceiling (2); a tall
///   box (12) and a short box (12), both rotated; a UV sphere (32 x 16, 960
///   triangles, smooth normals) resting on the short box. The camera is
///   inside the room at `(0, 1, 1.9)` looking at the back wall. The only
///   light is the emissive quad (`lights` is empty).
/// * `layers` (**512**): 256 parallel 2 x 2 quads facing +Z, centred on the
///   z axis, layer `i` at `z = -0.01 i` (nearest the camera first), 2
///   triangles each; camera at `(0, 0, 3)`, one directional light. Every
///   pixel near the image centre has 256 layers under it.
/// * `foliage` (**4096**): thin, long, randomly oriented triangles (length
///   0.15–0.45, width 0.004–0.02) with centres uniform in `[-1, 1]^3`;
///   camera at `(0, 0, 3.2)`, one directional light.
/// * `spheres` (**33794**): a 20 x 20 ground quad at `y = 0` (2 triangles),
///   then 8 x 8 UV spheres (24 x 12, 528 triangles each, smooth normals) of
///   radius 0.4 resting on it, row by row (`z` outer, `x` inner), each with
///   its own material (metallic rising along `x`, roughness along `z`);
///   camera at `(0, 5, 9)` looking at the origin, one directional light.
pub fn builtin(name: &str) -> Option<Scene> {
    Some(match name {
        "cornell" => cornell(),
        "layers" => layers(),
        "foliage" => foliage(),
        "spheres" => spheres(),
        _ => return None,
    })
}

/// A built-in scene uniformly scaled by `scale` about the origin and then
/// moved by `offset` (`p' = scale * p + offset`), for tiny, huge or far-away
/// variants. See [`Scene::transformed`] for arbitrary transforms.
pub fn builtin_scaled(name: &str, scale: f32, offset: Vec3) -> Option<Scene> {
    let m = Mat4::from_scale_rotation_translation(Vec3::splat(scale), Quat::IDENTITY, offset);
    builtin(name).map(|s| s.transformed(m))
}

/// SplitMix64: tiny, fast, good enough for scene generation.
#[derive(Debug)]
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `[0, 1)`.
    fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }
    /// Uniform on the unit sphere.
    fn unit_vector(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// A rectangle `center ± u ± v` (two triangles), facing `u x v`.
fn rect(b: &mut SceneBuilder, center: Vec3, u: Vec3, v: Vec3, material: u32) {
    let p = [
        center - u - v,
        center + u - v,
        center + u + v,
        center - u + v,
    ];
    b.push(Triangle::new(p[0], p[1], p[2]), material, None, None);
    b.push(Triangle::new(p[0], p[2], p[3]), material, None, None);
}

/// The unit cube `[-0.5, 0.5]^3` transformed by `m`, faces outwards, in the
/// order +X, -X, +Y, -Y, +Z, -Z (12 triangles).
fn cuboid(b: &mut SceneBuilder, m: Mat4, material: u32) {
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    ];
    for (n, u, v) in faces {
        let c = n * 0.5;
        let (u, v) = (u * 0.5, v * 0.5);
        let p = [c - u - v, c + u - v, c + u + v, c - u + v].map(|p| m.transform_point3(p));
        b.push(Triangle::new(p[0], p[1], p[2]), material, None, None);
        b.push(Triangle::new(p[0], p[2], p[3]), material, None, None);
    }
}

/// A UV sphere with `segs` longitudes and `rings` latitude bands, facing
/// outwards with smooth normals: `2 * segs * (rings - 1)` triangles, band by
/// band from the top (+Y) pole.
fn uv_sphere(
    b: &mut SceneBuilder,
    center: Vec3,
    radius: f32,
    segs: u32,
    rings: u32,
    material: u32,
) {
    let dir = |i: u32, j: u32| {
        let theta = PI * i as f32 / rings as f32;
        let phi = TAU * (j % segs) as f32 / segs as f32;
        if i == 0 {
            Vec3::Y
        } else if i == rings {
            Vec3::NEG_Y
        } else {
            Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            )
        }
    };
    let tri = |b: &mut SceneBuilder, d: [Vec3; 3]| {
        let p = d.map(|d| center + d * radius);
        b.push(
            Triangle::new(p[0], p[1], p[2]),
            material,
            Some(d.map(|d| d.to_array())),
            None,
        );
    };
    for i in 0..rings {
        for j in 0..segs {
            let (a, bb, c, d) = (dir(i, j), dir(i, j + 1), dir(i + 1, j + 1), dir(i + 1, j));
            if i != 0 {
                tri(b, [a, bb, c]);
            }
            if i + 1 != rings {
                tri(b, [a, c, d]);
            }
        }
    }
}

fn sun(direction: Vec3) -> Light {
    Light {
        name: "sun".to_string(),
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: direction.normalize(),
        color: [1.0, 0.97, 0.92],
        intensity: 3.0,
        range: None,
    }
}

fn cornell() -> Scene {
    let mut b = SceneBuilder::new("cornell");
    let white = b.add_material(Material::diffuse("white", [0.73, 0.73, 0.73]));
    let red = b.add_material(Material::diffuse("red", [0.63, 0.065, 0.05]));
    let green = b.add_material(Material::diffuse("green", [0.14, 0.45, 0.091]));
    let light = b.add_material(Material {
        emissive: [17.0, 12.0, 4.0],
        ..Material::diffuse("light", [0.78, 0.78, 0.78])
    });
    let metal = b.add_material(Material {
        name: "metal".to_string(),
        base_color: [0.95, 0.93, 0.88, 1.0],
        metallic: 1.0,
        roughness: 0.05,
        ..Material::default()
    });

    // Room: x in [-1, 1], y in [0, 2], z in [-1, 2]; normals point inwards.
    let (x, y0, y1, z0, z1) = (1.0, 0.0, 2.0, -1.0, 2.0);
    let (yc, zc) = ((y0 + y1) / 2.0, (z0 + z1) / 2.0);
    let (hy, hz) = ((y1 - y0) / 2.0, (z1 - z0) / 2.0);
    rect(
        &mut b,
        Vec3::new(0.0, y0, zc),
        Vec3::Z * hz,
        Vec3::X * x,
        white,
    ); // floor, +Y
    rect(
        &mut b,
        Vec3::new(0.0, y1, zc),
        Vec3::X * x,
        Vec3::Z * hz,
        white,
    ); // ceiling, -Y
    rect(
        &mut b,
        Vec3::new(0.0, yc, z0),
        Vec3::X * x,
        Vec3::Y * hy,
        white,
    ); // back, +Z
    rect(
        &mut b,
        Vec3::new(-x, yc, zc),
        Vec3::Y * hy,
        Vec3::Z * hz,
        red,
    ); // left, +X
    rect(
        &mut b,
        Vec3::new(x, yc, zc),
        Vec3::Z * hz,
        Vec3::Y * hy,
        green,
    ); // right, -X
    rect(
        &mut b,
        Vec3::new(0.0, yc, z1),
        Vec3::Y * hy,
        Vec3::X * x,
        white,
    ); // front, -Z
    rect(
        &mut b,
        Vec3::new(0.0, y1 - 0.02, -0.1),
        Vec3::X * 0.25,
        Vec3::Z * 0.25,
        light,
    ); // light, -Y

    let tall = Mat4::from_translation(Vec3::new(-0.35, 0.6, -0.35))
        * Mat4::from_rotation_y(0.3)
        * Mat4::from_scale(Vec3::new(0.55, 1.2, 0.55));
    cuboid(&mut b, tall, white);
    let short = Mat4::from_translation(Vec3::new(0.35, 0.3, 0.3))
        * Mat4::from_rotation_y(-0.3)
        * Mat4::from_scale(Vec3::new(0.55, 0.6, 0.55));
    cuboid(&mut b, short, white);
    uv_sphere(
        &mut b,
        Vec3::new(0.35, 0.6 + 0.22, 0.3),
        0.22,
        32,
        16,
        metal,
    );

    let mut cam = Camera::look_at(
        "camera",
        Vec3::new(0.0, 1.0, 1.9),
        Vec3::new(0.0, 1.0, -1.0),
        Vec3::Y,
        0.69,
    );
    cam.aspect = Some(1.0);
    b.scene.cameras.push(cam);
    b.finish()
}

fn layers() -> Scene {
    let mut b = SceneBuilder::new("layers");
    let colors = [
        [0.8, 0.2, 0.2],
        [0.2, 0.8, 0.2],
        [0.2, 0.2, 0.8],
        [0.8, 0.8, 0.2],
    ];
    let mats: Vec<u32> = colors
        .iter()
        .enumerate()
        .map(|(i, &c)| b.add_material(Material::diffuse(&format!("layer{i}"), c)))
        .collect();
    for i in 0..256u32 {
        let m = mats[i as usize % mats.len()];
        rect(
            &mut b,
            Vec3::new(0.0, 0.0, -0.01 * i as f32),
            Vec3::X,
            Vec3::Y,
            m,
        );
    }
    b.scene.cameras.push(Camera::look_at(
        "camera",
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::ZERO,
        Vec3::Y,
        0.6,
    ));
    b.scene.lights.push(sun(Vec3::new(-0.3, -0.5, -1.0)));
    b.finish()
}

fn foliage() -> Scene {
    let mut b = SceneBuilder::new("foliage");
    let greens = [[0.1, 0.45, 0.08], [0.2, 0.55, 0.1], [0.35, 0.5, 0.12]];
    let mats: Vec<u32> = greens
        .iter()
        .enumerate()
        .map(|(i, &c)| b.add_material(Material::diffuse(&format!("leaf{i}"), c)))
        .collect();
    let mut rng = Rng(0x00F0_11A6_E5EE_D001);
    for k in 0..4096usize {
        let c = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let d = rng.unit_vector();
        let (_, perp) = crate::model::orthonormal_up(d, rng.unit_vector());
        let half_len = 0.5 * rng.range(0.15, 0.45);
        let half_w = 0.5 * rng.range(0.004, 0.02);
        let base = c - d * half_len;
        let tri = Triangle::new(base - perp * half_w, base + perp * half_w, c + d * half_len);
        b.push(tri, mats[k % mats.len()], None, None);
    }
    b.scene.cameras.push(Camera::look_at(
        "camera",
        Vec3::new(0.0, 0.0, 3.2),
        Vec3::ZERO,
        Vec3::Y,
        0.8,
    ));
    b.scene.lights.push(sun(Vec3::new(0.2, -1.0, -0.4)));
    b.finish()
}

fn spheres() -> Scene {
    let mut b = SceneBuilder::new("spheres");
    let ground = b.add_material(Material::diffuse("ground", [0.5, 0.5, 0.5]));
    rect(&mut b, Vec3::ZERO, Vec3::Z * 10.0, Vec3::X * 10.0, ground);
    let mut rng = Rng(0x0000_005E_ED5F_E4E5);
    for row in 0..8 {
        for col in 0..8 {
            let rgb = [
                rng.range(0.1, 0.9),
                rng.range(0.1, 0.9),
                rng.range(0.1, 0.9),
            ];
            let m = b.add_material(Material {
                metallic: col as f32 / 7.0,
                roughness: 0.05 + 0.95 * row as f32 / 7.0,
                ..Material::diffuse(&format!("sphere{row}{col}"), rgb)
            });
            let center = Vec3::new(-3.5 + col as f32, 0.4, -3.5 + row as f32);
            uv_sphere(&mut b, center, 0.4, 24, 12, m);
        }
    }
    b.scene.cameras.push(Camera::look_at(
        "camera",
        Vec3::new(0.0, 5.0, 9.0),
        Vec3::ZERO,
        Vec3::Y,
        0.7,
    ));
    b.scene.lights.push(sun(Vec3::new(-0.4, -1.0, -0.3)));
    b.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_is_uniform_enough() {
        let mut r = Rng(1);
        let mean = (0..10000).map(|_| r.f32()).sum::<f32>() / 10000.0;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
        assert!((0..1000).map(|_| r.f32()).all(|x| (0.0..1.0).contains(&x)));
    }

    #[test]
    fn sphere_faces_outwards() {
        let mut b = SceneBuilder::new("s");
        uv_sphere(&mut b, Vec3::new(1.0, 2.0, 3.0), 0.5, 8, 5, 0);
        let s = b.finish();
        assert_eq!(s.len(), 2 * 8 * 4);
        for t in &s.triangles {
            let n = crate::builder::face_normal(t);
            let c = (t.vertex(0) + t.vertex(1) + t.vertex(2)) / 3.0 - Vec3::new(1.0, 2.0, 3.0);
            assert!(n.dot(c) > 0.0, "{t:?}");
        }
    }

    #[test]
    fn cuboid_faces_outwards() {
        let mut b = SceneBuilder::new("c");
        cuboid(
            &mut b,
            Mat4::from_rotation_y(0.4) * Mat4::from_scale(Vec3::new(1.0, 2.0, 3.0)),
            0,
        );
        let s = b.finish();
        assert_eq!(s.len(), 12);
        for t in &s.triangles {
            let n = crate::builder::face_normal(t);
            let c = (t.vertex(0) + t.vertex(1) + t.vertex(2)) / 3.0;
            assert!(n.dot(c) > 0.0, "{t:?}");
        }
    }

    #[test]
    fn cornell_walls_face_inwards() {
        let s = cornell();
        let inside = Vec3::new(0.0, 1.0, 0.5);
        for t in &s.triangles[..14] {
            let n = crate::builder::face_normal(t);
            assert!(n.dot(inside - t.vertex(0)) > 0.0, "{t:?}");
        }
    }
}
