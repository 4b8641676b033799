//! Animated glTF: node channels with every interpolation, skins and morph
//! targets posed at chosen times, checked against vertices computed by hand;
//! the assets of `assimp-testmodels` that move; and the named errors for
//! animation data a pose could not use.
#![allow(clippy::unwrap_used)]

mod common;

use std::f32::consts::FRAC_1_SQRT_2;

use common::{assimp_models, f32_bytes, glb, write};
use dirt_scene::{AnimatedScene, SceneError, Vec3, load_animated, open_animated};

/// A small GLB built from float arrays, each its own buffer view and accessor.
#[derive(Default)]
struct Doc {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
}

impl Doc {
    /// Adds an accessor of `ty` (`SCALAR`, `VEC3`, ...) over `data`; returns its index.
    fn floats(&mut self, data: &[f32], ty: &str) -> usize {
        let n = match ty {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            "MAT4" => 16,
            _ => panic!("type {ty}"),
        };
        let offset = self.bin.len();
        self.bin.extend(f32_bytes(data));
        self.views.push(format!(
            r#"{{"buffer": 0, "byteOffset": {offset}, "byteLength": {}}}"#,
            data.len() * 4
        ));
        let minmax = if ty == "SCALAR" && data.iter().all(|x| x.is_finite()) && !data.is_empty() {
            let lo = data.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = data.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            format!(r#", "min": [{lo}], "max": [{hi}]"#)
        } else if ty == "SCALAR" {
            r#", "min": [0], "max": [1]"#.to_string()
        } else {
            String::new()
        };
        self.accessors.push(format!(
            r#"{{"bufferView": {}, "componentType": 5126, "count": {}, "type": "{ty}"{minmax}}}"#,
            self.views.len() - 1,
            data.len() / n
        ));
        self.accessors.len() - 1
    }

    /// Adds an accessor of four unsigned shorts per element (joints).
    fn joints(&mut self, data: &[u16]) -> usize {
        let offset = self.bin.len();
        self.bin.extend(data.iter().flat_map(|x| x.to_le_bytes()));
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(format!(
            r#"{{"buffer": 0, "byteOffset": {offset}, "byteLength": {}}}"#,
            data.len() * 2
        ));
        self.accessors.push(format!(
            r#"{{"bufferView": {}, "componentType": 5123, "count": {}, "type": "VEC4"}}"#,
            self.views.len() - 1,
            data.len() / 4
        ));
        self.accessors.len() - 1
    }

    /// The GLB with these top-level members besides buffers, views and accessors.
    fn glb(&self, members: &str) -> Vec<u8> {
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "buffers": [{{"byteLength": {}}}],
                "bufferViews": [{}], "accessors": [{}], {members}}}"#,
            self.bin.len(),
            self.views.join(","),
            self.accessors.join(",")
        );
        glb(&json, &self.bin)
    }
}

/// The triangle (0,0,0), (1,0,0), (0,1,0) on node 0, animated by one channel
/// of `path` with `keys` and `values` under `interpolation`. `extra` adds to
/// the mesh's primitive (morph targets) and `mesh_extra` to the mesh.
fn one_channel(
    path: &str,
    interpolation: &str,
    keys: &[f32],
    values: &[f32],
    value_type: &str,
    with_target: bool,
) -> (tempfile::TempDir, std::path::PathBuf) {
    let mut d = Doc::default();
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let targets = if with_target {
        let t = d.floats(&[0., 0., 1., 0., 0., 1., 0., 0., 1.], "VEC3");
        format!(r#", "targets": [{{"POSITION": {t}}}]"#)
    } else {
        String::new()
    };
    let input = d.floats(keys, "SCALAR");
    let output = d.floats(values, value_type);
    let members = format!(
        r#""nodes": [{{"mesh": 0}}], "scenes": [{{"nodes": [0]}}], "scene": 0,
           "meshes": [{{"primitives": [{{"attributes": {{"POSITION": {pos}}}{targets}}}]}}],
           "animations": [{{"channels": [{{"sampler": 0, "target": {{"node": 0, "path": "{path}"}}}}],
                            "samplers": [{{"input": {input}, "output": {output}, "interpolation": "{interpolation}"}}]}}]"#
    );
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "anim.glb", d.glb(&members));
    (dir, p)
}

fn corners(s: &AnimatedScene) -> Vec<Vec3> {
    s.scene
        .triangles
        .iter()
        .flat_map(|t| (0..3).map(|k| t.vertex(k)))
        .collect()
}

fn assert_near(got: &[Vec3], want: &[Vec3], tol: f32, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: vertex count");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (*g - *w).abs().max_element() <= tol,
            "{what}: vertex {i} is {g}, expected {w}"
        );
    }
}

const TRI: [Vec3; 3] = [Vec3::ZERO, Vec3::X, Vec3::Y];

fn moved(by: impl Fn(Vec3) -> Vec3) -> Vec<Vec3> {
    TRI.iter().map(|&v| by(v)).collect()
}

#[test]
fn translation_under_each_interpolation() {
    let (_d, p) = one_channel(
        "translation",
        "LINEAR",
        &[0.0, 1.0],
        &[0., 0., 0., 2., 0., 0.],
        "VEC3",
        false,
    );
    let mut s = load_animated(&p).unwrap();
    assert!(s.is_animated());
    assert_eq!(s.duration(), 1.0);
    for (t, x) in [
        (-1.0, 0.0),
        (0.0, 0.0),
        (0.25, 0.5),
        (0.5, 1.0),
        (1.0, 2.0),
        (3.0, 2.0),
    ] {
        s.pose(t).unwrap();
        assert_near(
            &corners(&s),
            &moved(|v| v + Vec3::new(x, 0., 0.)),
            0.0,
            &format!("LINEAR t={t}"),
        );
    }

    let (_d, p) = one_channel(
        "translation",
        "STEP",
        &[0.0, 1.0],
        &[0., 0., 0., 2., 0., 0.],
        "VEC3",
        false,
    );
    let mut s = load_animated(&p).unwrap();
    for (t, x) in [(0.0, 0.0), (0.99, 0.0), (1.0, 2.0)] {
        s.pose(t).unwrap();
        assert_near(
            &corners(&s),
            &moved(|v| v + Vec3::new(x, 0., 0.)),
            0.0,
            &format!("STEP t={t}"),
        );
    }

    // Hermite: v0 = 0, out-tangent b0 = 3, v1 = 1, in-tangent a1 = 0; at
    // s = 1/2: 0.5·0 + 0.125·3 + 0.5·1 − 0.125·0 = 0.875 (time step 1).
    let (_d, p) = one_channel(
        "translation",
        "CUBICSPLINE",
        &[0.0, 1.0],
        &[
            0., 0., 0., /* v0 */ 0., 0., 0., /* b0 */ 3., 0., 0., //
            /* a1 */ 0., 0., 0., /* v1 */ 1., 0., 0., /* b1 */ 0., 0., 0.,
        ],
        "VEC3",
        false,
    );
    let mut s = load_animated(&p).unwrap();
    for (t, x) in [(0.0, 0.0), (0.5, 0.875), (1.0, 1.0)] {
        s.pose(t).unwrap();
        assert_near(
            &corners(&s),
            &moved(|v| v + Vec3::new(x, 0., 0.)),
            1e-6,
            &format!("CUBICSPLINE t={t}"),
        );
    }
}

#[test]
fn rotation_is_slerped_and_scale_interpolated() {
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let (_d, p) = one_channel(
        "rotation",
        "LINEAR",
        &[0.0, 2.0],
        &[0., 0., 0., 1., 0., 0., h, h],
        "VEC4",
        false,
    );
    let mut s = load_animated(&p).unwrap();
    // Halfway from no turn to 90° about z: 45°.
    s.pose(1.0).unwrap();
    let (c, n) = (45f32.to_radians().cos(), 45f32.to_radians().sin());
    let want = [Vec3::ZERO, Vec3::new(c, n, 0.), Vec3::new(-n, c, 0.)];
    assert_near(&corners(&s), &want, 1e-6, "rotation t=1");
    // A quarter of the way: 22.5°, the angle slerp gives (a lerp would not).
    s.pose(0.5).unwrap();
    let (c, n) = (22.5f32.to_radians().cos(), 22.5f32.to_radians().sin());
    let want = [Vec3::ZERO, Vec3::new(c, n, 0.), Vec3::new(-n, c, 0.)];
    assert_near(&corners(&s), &want, 1e-6, "rotation t=0.5");

    let (_d, p) = one_channel(
        "scale",
        "LINEAR",
        &[0.0, 1.0],
        &[1., 1., 1., 3., 3., 3.],
        "VEC3",
        false,
    );
    let mut s = load_animated(&p).unwrap();
    s.pose(0.5).unwrap();
    assert_near(&corners(&s), &moved(|v| 2.0 * v), 0.0, "scale t=0.5");
}

#[test]
fn morph_weights_move_the_vertices() {
    let (_d, p) = one_channel(
        "weights",
        "LINEAR",
        &[0.0, 1.0],
        &[0.0, 1.0],
        "SCALAR",
        true,
    );
    let mut s = load_animated(&p).unwrap();
    for (t, z) in [(0.0, 0.0), (0.25, 0.25), (1.0, 1.0)] {
        s.pose(t).unwrap();
        assert_near(
            &corners(&s),
            &moved(|v| v + Vec3::new(0., 0., z)),
            1e-7,
            &format!("weights t={t}"),
        );
    }
}

/// Node 1 is the joint (a translation channel), node 0 the skinned mesh.
fn skinned(joints: &[u16], weights: &[f32], ibm_x: f32) -> (tempfile::TempDir, std::path::PathBuf) {
    let mut d = Doc::default();
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let j = d.joints(joints);
    let w = d.floats(weights, "VEC4");
    let mut ibm = [0f32; 16];
    for i in 0..4 {
        ibm[5 * i] = 1.0;
    }
    ibm[12] = ibm_x;
    let ibm = d.floats(&ibm, "MAT4");
    let input = d.floats(&[0.0, 1.0], "SCALAR");
    let output = d.floats(&[0., 0., 0., 0., 4., 0.], "VEC3");
    let members = format!(
        r#""nodes": [{{"mesh": 0, "skin": 0, "translation": [100, 0, 0]}}, {{"translation": [0, 0, 0]}}],
           "scenes": [{{"nodes": [0, 1]}}], "scene": 0,
           "skins": [{{"joints": [1], "inverseBindMatrices": {ibm}}}],
           "meshes": [{{"primitives": [{{"attributes": {{"POSITION": {pos}, "JOINTS_0": {j}, "WEIGHTS_0": {w}}}}}]}}],
           "animations": [{{"channels": [{{"sampler": 0, "target": {{"node": 1, "path": "translation"}}}}],
                            "samplers": [{{"input": {input}, "output": {output}}}]}}]"#
    );
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "skin.glb", d.glb(&members));
    (dir, p)
}

#[test]
fn a_skinned_mesh_follows_its_joint_and_ignores_its_node() {
    // One joint, weight 1 everywhere, inverse bind translating x by -1:
    // vertex = joint(t) · (p − (1,0,0)); the mesh node's +100 is ignored.
    let (_d, p) = skinned(
        &[0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0],
        &[1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0.],
        -1.0,
    );
    let mut s = load_animated(&p).unwrap();
    s.pose(0.5).unwrap();
    assert_near(
        &corners(&s),
        &moved(|v| v + Vec3::new(-1., 2., 0.)),
        0.0,
        "skin t=0.5",
    );
    // The static loader keeps the bind pose under the node transform.
    let fixed = dirt_scene::load(&p).unwrap();
    assert_eq!(fixed.triangles[0].vertex(1), Vec3::new(101., 0., 0.));
}

#[test]
fn simple_skin_bends_as_computed_by_hand() {
    let p = assimp_models().join("glTF2/simple_skin/simple_skin.gltf");
    let rest = dirt_scene::load(&p).unwrap();
    let mut s = load_animated(&p).unwrap();
    let clips = s.clips();
    assert_eq!(clips.len(), 1);
    assert_eq!(clips[0].duration, 5.5);
    assert!(s.is_animated());
    // Joint 0: node 1 at (0,1,0); joint 1: node 2 below it, turning about z.
    // Both inverse binds translate by (−0.5, −1, 0). A vertex at height y
    // has weight y/2 on joint 1 and the rest on joint 0.
    for (t, angle) in [(0.0f32, 0.0f32), (1.0, 90.0), (0.25, 22.5), (4.0, -90.0)] {
        s.pose(t).unwrap();
        // The file's 0.707 and 0.383 keys are turns of 90° and 45°, to 1e-3.
        let (sin, cos) = angle.to_radians().sin_cos();
        let want: Vec<Vec3> = rest
            .triangles
            .iter()
            .flat_map(|t| (0..3).map(|k| t.vertex(k)))
            .map(|v| {
                let w1 = v.y / 2.0;
                let p0 = Vec3::new(v.x - 0.5, v.y, 0.0);
                let (a, b) = (v.x - 0.5, v.y - 1.0);
                let p1 = Vec3::new(cos * a - sin * b, 1.0 + sin * a + cos * b, 0.0);
                (1.0 - w1) * p0 + w1 * p1
            })
            .collect();
        assert_near(&corners(&s), &want, 2e-3, &format!("simple_skin t={t}"));
    }
}

#[test]
fn animated_morph_cube_follows_its_weights() {
    let p = assimp_models()
        .join("glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf");
    let rest = dirt_scene::load(&p).unwrap();
    let mut s = open_animated(p.to_str().unwrap()).unwrap();
    assert!(s.is_animated());
    assert!((s.duration() - 4.2).abs() < 1e-3, "{}", s.duration());
    // Time 0: both weights 0, the base geometry, to the bit.
    s.pose(0.0).unwrap();
    assert_eq!(s.scene.triangles, rest.triangles);
    assert_eq!(s.scene.tri_normals, rest.tri_normals);
    // Key 48 (t ≈ 1.6): weights (1, 0). The file's vertex 2, (0.01, −0.01,
    // 0.01), moves by target 0's (0, 0.018932531, 0) to y = 0.008932531;
    // the node scales by 100 and turns by the quaternion (0, h, −h, 0).
    s.pose(1.599_999_8).unwrap();
    let node = glam::Mat4::from_scale_rotation_translation(
        Vec3::splat(100.0),
        glam::Quat::from_xyzw(0.0, FRAC_1_SQRT_2, -FRAC_1_SQRT_2, 0.0),
        Vec3::ZERO,
    );
    let want = node.transform_point3(Vec3::new(0.01, 0.008_932_531, 0.01));
    let c = corners(&s);
    assert!(
        c.iter().any(|v| (*v - want).abs().max_element() < 1e-3),
        "no vertex near {want}"
    );
    assert!(
        !rest
            .triangles
            .iter()
            .flat_map(|t| (0..3).map(|k| t.vertex(k)))
            .any(|v| (v - want).abs().max_element() < 1e-3)
    );
    // The file's normal deltas are all zero: the normals stay.
    assert_eq!(s.scene.tri_normals, rest.tri_normals);
}

#[test]
fn scenes_without_a_rig_are_fixed() {
    let mut s = open_animated("cornell").unwrap();
    assert!(!s.is_animated());
    assert_eq!(s.duration(), 0.0);
    let before = s.scene.clone();
    s.pose(3.0).unwrap();
    assert_eq!(s.scene, before);
    let p = assimp_models().join("glTF2/BoxTextured-glTF-Binary/BoxTextured.glb");
    let s = open_animated(p.to_str().unwrap()).unwrap();
    assert!(!s.is_animated());
    assert_eq!(s.scene, dirt_scene::load(&p).unwrap());
}

fn animation_error(r: Result<AnimatedScene, SceneError>) -> String {
    match r {
        Err(e @ SceneError::Animation { .. }) => e.to_string(),
        Err(e) => panic!("expected SceneError::Animation, got {e}"),
        Ok(_) => panic!("expected SceneError::Animation, loaded"),
    }
}

#[test]
fn bad_animation_data_is_refused_by_name() {
    // Three values for two LINEAR keys.
    let (_d, p) = one_channel(
        "translation",
        "LINEAR",
        &[0.0, 1.0],
        &[0.; 9],
        "VEC3",
        false,
    );
    let e = animation_error(load_animated(&p));
    assert!(e.contains("2 keys but 9 output values"), "{e}");
    // A cubic spline needs three values a key.
    let (_d, p) = one_channel(
        "translation",
        "CUBICSPLINE",
        &[0.0, 1.0],
        &[0.; 6],
        "VEC3",
        false,
    );
    let e = animation_error(load_animated(&p));
    assert!(e.contains("needs 18"), "{e}");
    let (_d, p) = one_channel(
        "translation",
        "LINEAR",
        &[0.0, f32::NAN],
        &[0.; 6],
        "VEC3",
        false,
    );
    let e = animation_error(load_animated(&p));
    assert!(e.contains("key 1 is NaN"), "{e}");
    let (_d, p) = one_channel(
        "translation",
        "LINEAR",
        &[1.0, 0.5],
        &[0.; 6],
        "VEC3",
        false,
    );
    let e = animation_error(load_animated(&p));
    assert!(e.contains("key times must increase"), "{e}");
    let (_d, p) = one_channel(
        "translation",
        "LINEAR",
        &[0.0, 1.0],
        &[0., 0., 0., f32::INFINITY, 0., 0.],
        "VEC3",
        false,
    );
    let e = animation_error(load_animated(&p));
    assert!(e.contains("values must be finite"), "{e}");
    let (_d, p) = one_channel(
        "weights",
        "LINEAR",
        &[0.0, 1.0],
        &[0.0, 1.0],
        "SCALAR",
        false,
    );
    let e = animation_error(load_animated(&p));
    assert!(e.contains("no morph targets"), "{e}");
    // The static loader does not read animations: these files still load.
    assert!(dirt_scene::load(&p).is_ok());

    let w = [1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0.];
    let (_d, p) = skinned(&[0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0], &w, 0.0);
    let e = animation_error(load_animated(&p));
    assert!(
        e.contains("vertex 1 names joint 1, but its skin has 1 joints"),
        "{e}"
    );
    let (_d, p) = skinned(
        &[0; 12],
        &[1., 0., 0., 0., 0.5, 0., 0., 0., 1., 0., 0., 0.],
        0.0,
    );
    let e = animation_error(load_animated(&p));
    assert!(e.contains("vertex 1") && e.contains("sum to one"), "{e}");

    // A time that is not a number.
    let (_d, p) = one_channel(
        "translation",
        "LINEAR",
        &[0.0, 1.0],
        &[0.; 6],
        "VEC3",
        false,
    );
    let mut s = load_animated(&p).unwrap();
    assert!(matches!(
        s.pose(f32::NAN),
        Err(SceneError::Animation { .. })
    ));
}

#[test]
fn every_channel_under_step_and_cubic_spline() {
    let h = FRAC_1_SQRT_2;
    // Scale, STEP: the first key's value holds until the second key.
    let (_d, p) = one_channel(
        "scale",
        "STEP",
        &[0.0, 1.0],
        &[1., 1., 1., 3., 3., 3.],
        "VEC3",
        false,
    );
    let mut s = load_animated(&p).unwrap();
    s.pose(0.5).unwrap();
    assert_near(&corners(&s), &moved(|v| v), 0.0, "scale STEP t=0.5");
    s.pose(1.0).unwrap();
    assert_near(&corners(&s), &moved(|v| 3.0 * v), 0.0, "scale STEP t=1");

    // Rotation, STEP: no turn until the key of 90°.
    let (_d, p) = one_channel(
        "rotation",
        "STEP",
        &[0.0, 1.0],
        &[0., 0., 0., 1., 0., 0., h, h],
        "VEC4",
        false,
    );
    let mut s = load_animated(&p).unwrap();
    s.pose(0.5).unwrap();
    assert_near(&corners(&s), &moved(|v| v), 0.0, "rotation STEP t=0.5");
    s.pose(1.0).unwrap();
    let quarter = [Vec3::ZERO, Vec3::Y, -Vec3::X];
    assert_near(&corners(&s), &quarter, 1e-6, "rotation STEP t=1");

    // Rotation, CUBICSPLINE with zero tangents: halfway, the spline is the
    // mean of the two keys, (0, 0, h/2, 1/2 + h/2), normalised: a turn of 45°.
    let (_d, p) = one_channel(
        "rotation",
        "CUBICSPLINE",
        &[0.0, 1.0],
        &[
            0., 0., 0., 0., /* v0 */ 0., 0., 0., 1., /* b0 */ 0., 0., 0., 0., //
            /* a1 */ 0., 0., 0., 0., /* v1 */ 0., 0., h, h, /* b1 */ 0., 0., 0., 0.,
        ],
        "VEC4",
        false,
    );
    let mut s = load_animated(&p).unwrap();
    s.pose(0.5).unwrap();
    let (c, n) = (45f32.to_radians().cos(), 45f32.to_radians().sin());
    let want = [Vec3::ZERO, Vec3::new(c, n, 0.), Vec3::new(-n, c, 0.)];
    assert_near(&corners(&s), &want, 1e-6, "rotation CUBICSPLINE t=0.5");

    // Morph weights, STEP and CUBICSPLINE (zero tangents: 0.5 at halfway).
    let (_d, p) = one_channel("weights", "STEP", &[0.0, 1.0], &[0.0, 1.0], "SCALAR", true);
    let mut s = load_animated(&p).unwrap();
    s.pose(0.5).unwrap();
    assert_near(&corners(&s), &moved(|v| v), 0.0, "weights STEP t=0.5");
    s.pose(1.0).unwrap();
    assert_near(
        &corners(&s),
        &moved(|v| v + Vec3::Z),
        0.0,
        "weights STEP t=1",
    );
    let (_d, p) = one_channel(
        "weights",
        "CUBICSPLINE",
        &[0.0, 1.0],
        &[0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        "SCALAR",
        true,
    );
    let mut s = load_animated(&p).unwrap();
    s.pose(0.5).unwrap();
    assert_near(
        &corners(&s),
        &moved(|v| v + Vec3::new(0., 0., 0.5)),
        1e-7,
        "weights CUBICSPLINE t=0.5",
    );
}
