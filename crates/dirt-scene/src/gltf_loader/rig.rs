//! What an animated load records beyond the static scene: each mesh
//! instance's node path and skin, each primitive's object-space vertices,
//! morph targets, joints and weights, and the triangles it made; then the
//! nodes, skins and animation clips. Every accessor goes through the same
//! bounds-checked decoding as the geometry, and every inconsistency a pose
//! would trip over is refused here with [`SceneError::Animation`].

use dirt_math::Vec3;
use glam::{Mat4, Quat};
use gltf::accessor::Dimensions;
use gltf::animation::{Interpolation as GltfInterpolation, Property as GltfProperty};
use gltf::mesh::Semantic;

use super::Ctx;
use super::accessors::read_floats;
use crate::SceneError;
use crate::animation::{
    Channel, Clip, Influence, Instance, Interpolation, Node, Primitive, Property, Rig, Skin, Target,
};

/// How far the four weights of a vertex may sum from one (quantised
/// `u8` weights are off by up to 4 · 0.5/255).
const WEIGHT_SUM_TOLERANCE: f32 = 0.01;

/// Filled by the node walk.
#[derive(Debug, Default)]
pub(super) struct Recorder {
    /// Node indices from the root to the node being visited.
    pub path: Vec<usize>,
    pub instances: Vec<Instance>,
    pub primitives: Vec<Primitive>,
    pub cameras: Vec<Vec<usize>>,
    pub lights: Vec<Vec<usize>>,
    morphs: bool,
}

impl Recorder {
    /// A mesh met at the current path.
    pub fn enter_mesh(&mut self, skin: Option<usize>, weights: Option<&[f32]>) {
        self.instances.push(Instance {
            path: self.path.clone(),
            skin,
            weights: weights.map(<[f32]>::to_vec).unwrap_or_default(),
        });
    }
}

fn animation_err(ctx: &Ctx, location: &str, problem: String) -> SceneError {
    SceneError::Animation {
        path: ctx.path.to_path_buf(),
        location: location.to_string(),
        problem,
    }
}

fn vec3s(values: &[f32]) -> Vec<Vec3> {
    values
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect()
}

/// Records a primitive of the current mesh instance: `corners` are the
/// vertex indices of the triangles it added from `first` on.
pub(super) fn record_primitive(
    ctx: &mut Ctx,
    location: &str,
    prim: &gltf::Primitive,
    first: usize,
    corners: Vec<[u32; 3]>,
    positions: &[f32],
    normals: Option<Vec<f32>>,
) -> Result<(), SceneError> {
    let n = positions.len() / 3;
    let vec3_attr = |ctx: &Ctx, acc: Option<gltf::Accessor>, name: &str| {
        let Some(acc) = acc else {
            return Ok(None);
        };
        let v = read_floats(ctx, &acc, Dimensions::Vec3, location, name)?;
        if acc.count() != n {
            return Err(ctx.accessor_err(
                location,
                name,
                format!("has {} elements but POSITION has {n}", acc.count()),
            ));
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(animation_err(
                ctx,
                location,
                format!("{name}: component {i} is not finite"),
            ));
        }
        Ok(Some(vec3s(&v)))
    };
    let mut targets = Vec::new();
    for (k, t) in prim.morph_targets().enumerate() {
        targets.push(Target {
            positions: vec3_attr(ctx, t.positions(), &format!("target {k} POSITION"))?,
            normals: vec3_attr(ctx, t.normals(), &format!("target {k} NORMAL"))?,
        });
    }
    let Some(instance) = ctx
        .rig
        .as_ref()
        .map(|r| r.instances.len().saturating_sub(1))
    else {
        return Ok(());
    };
    let skin = ctx
        .rig
        .as_ref()
        .and_then(|r| r.instances.last())
        .and_then(|i| i.skin);
    let influences = match skin {
        Some(_) => read_influences(ctx, prim, location, n)?,
        None => None,
    };
    let normals = normals.map(|v| vec3s(&v));
    if let Some(r) = ctx.rig.as_mut() {
        r.morphs |= !targets.is_empty();
        r.primitives.push(Primitive {
            instance,
            location: location.to_string(),
            first,
            corners,
            positions: vec3s(positions),
            normals,
            targets,
            influences,
        });
    }
    Ok(())
}

/// `JOINTS_0` and `WEIGHTS_0` of a skinned primitive, weights normalised.
/// Joint indices are checked against the skin when the rig is built.
fn read_influences(
    ctx: &mut Ctx,
    prim: &gltf::Primitive,
    location: &str,
    n: usize,
) -> Result<Option<Vec<Influence>>, SceneError> {
    let (Some(j_acc), Some(w_acc)) = (
        prim.get(&Semantic::Joints(0)),
        prim.get(&Semantic::Weights(0)),
    ) else {
        ctx.b.warn(format!(
            "{location}: skinned mesh without JOINTS_0 and WEIGHTS_0; it follows its node"
        ));
        return Ok(None);
    };
    if prim.get(&Semantic::Joints(1)).is_some() {
        ctx.b.warn(format!(
            "{location}: only the first four joint influences (JOINTS_0) are used"
        ));
    }
    let joints = read_floats(ctx, &j_acc, Dimensions::Vec4, location, "JOINTS_0")?;
    let weights = read_floats(ctx, &w_acc, Dimensions::Vec4, location, "WEIGHTS_0")?;
    for (acc, name) in [(&j_acc, "JOINTS_0"), (&w_acc, "WEIGHTS_0")] {
        if acc.count() != n {
            return Err(ctx.accessor_err(
                location,
                name,
                format!("has {} elements but POSITION has {n}", acc.count()),
            ));
        }
    }
    let mut out = Vec::with_capacity(n);
    for (v, (j, w)) in joints
        .chunks_exact(4)
        .zip(weights.chunks_exact(4))
        .enumerate()
    {
        let sum: f32 = w.iter().sum();
        if !sum.is_finite()
            || w.iter().any(|&x| x < 0.0)
            || (sum - 1.0).abs() > WEIGHT_SUM_TOLERANCE
        {
            return Err(animation_err(
                ctx,
                location,
                format!(
                    "WEIGHTS_0 of vertex {v} are {w:?}, summing to {sum}: skin weights must be non-negative and sum to one"
                ),
            ));
        }
        if j.iter()
            .any(|&x| x < 0.0 || x.fract() != 0.0 || !x.is_finite())
        {
            return Err(animation_err(
                ctx,
                location,
                format!("JOINTS_0 of vertex {v} are {j:?}: not joint indices"),
            ));
        }
        out.push((
            [j[0] as u32, j[1] as u32, j[2] as u32, j[3] as u32],
            [w[0] / sum, w[1] / sum, w[2] / sum, w[3] / sum],
        ));
    }
    Ok(Some(out))
}

/// The rig of a walked document, or `None` when nothing in it can move
/// (no animation, skin or morph target): such a scene is fixed.
pub(super) fn build(
    ctx: &Ctx,
    doc: &gltf::Document,
    recorder: Recorder,
) -> Result<Option<Rig>, SceneError> {
    let has_skin = recorder.instances.iter().any(|i| i.skin.is_some());
    if doc.animations().len() == 0 && !has_skin && !recorder.morphs {
        return Ok(None);
    }
    let mut nodes: Vec<Node> = doc
        .nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            Node {
                matrix: Mat4::from_cols_array_2d(&n.transform().matrix()),
                translation: Vec3::from_array(t),
                rotation: Quat::from_array(r),
                scale: Vec3::from_array(s),
                parent: None,
                weights: n.weights().map(<[f32]>::to_vec),
            }
        })
        .collect();
    for n in doc.nodes() {
        for c in n.children() {
            if let Some(child) = nodes.get_mut(c.index()) {
                child.parent.get_or_insert(n.index());
            }
        }
    }
    let skins = read_skins(ctx, doc)?;
    for p in &recorder.primitives {
        let skin = recorder
            .instances
            .get(p.instance)
            .and_then(|i| i.skin)
            .and_then(|s| skins.get(s));
        if let (Some(skin), Some(inf)) = (skin, &p.influences)
            && let Some((v, j)) = inf.iter().enumerate().find_map(|(v, (js, ws))| {
                js.iter()
                    .zip(ws)
                    .find(|&(&j, &w)| w > 0.0 && j as usize >= skin.joints.len())
                    .map(|(&j, _)| (v, j))
            })
        {
            return Err(animation_err(
                ctx,
                &p.location,
                format!(
                    "vertex {v} names joint {j}, but its skin has {} joints",
                    skin.joints.len()
                ),
            ));
        }
    }
    let clips = read_clips(ctx, doc)?;
    Ok(Some(Rig::new(
        ctx.path.to_path_buf(),
        nodes,
        recorder.instances,
        recorder.primitives,
        skins,
        clips,
        recorder.cameras,
        recorder.lights,
    )))
}

fn read_skins(ctx: &Ctx, doc: &gltf::Document) -> Result<Vec<Skin>, SceneError> {
    let mut skins = Vec::new();
    for skin in doc.skins() {
        let location = format!("skin {}", skin.index());
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let inverse_bind = match skin.inverse_bind_matrices() {
            Some(acc) => {
                let m = read_floats(
                    ctx,
                    &acc,
                    Dimensions::Mat4,
                    &location,
                    "inverseBindMatrices",
                )?;
                if acc.count() < joints.len() {
                    return Err(animation_err(
                        ctx,
                        &location,
                        format!(
                            "{} inverse bind matrices for {} joints",
                            acc.count(),
                            joints.len()
                        ),
                    ));
                }
                if m.iter().any(|x| !x.is_finite()) {
                    return Err(animation_err(
                        ctx,
                        &location,
                        "an inverse bind matrix is not finite".to_string(),
                    ));
                }
                m.chunks_exact(16).map(Mat4::from_cols_slice).collect()
            }
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        skins.push(Skin {
            joints,
            inverse_bind,
        });
    }
    Ok(skins)
}

fn read_clips(ctx: &Ctx, doc: &gltf::Document) -> Result<Vec<Clip>, SceneError> {
    // Morph target counts of the meshes each node holds (for weights channels).
    let targets_of = |node: usize| -> Option<usize> {
        let mesh = doc.nodes().nth(node)?.mesh()?;
        mesh.primitives().map(|p| p.morph_targets().len()).max()
    };
    let mut clips = Vec::new();
    for anim in doc.animations() {
        let name = anim.name().unwrap_or_default().to_string();
        let mut channels = Vec::new();
        let mut duration = 0f32;
        for (ci, ch) in anim.channels().enumerate() {
            let location = match anim.name() {
                Some(n) => format!("animation {} '{n}' channel {ci}", anim.index()),
                None => format!("animation {} channel {ci}", anim.index()),
            };
            let node = ch.target().node().index();
            let sampler = ch.sampler();
            // `property()` unwraps the path, which a malformed file may leave invalid.
            let path = doc
                .as_json()
                .animations
                .get(anim.index())
                .and_then(|a| a.channels.get(ci))
                .map(|c| &c.target.path);
            if !matches!(path, Some(gltf::json::validation::Checked::Valid(_))) {
                return Err(animation_err(
                    ctx,
                    &location,
                    "targets a path that is not translation, rotation, scale or weights".into(),
                ));
            }
            let (property, dims, width) = match ch.target().property() {
                GltfProperty::Translation => (Property::Translation, Dimensions::Vec3, 3),
                GltfProperty::Rotation => (Property::Rotation, Dimensions::Vec4, 4),
                GltfProperty::Scale => (Property::Scale, Dimensions::Vec3, 3),
                GltfProperty::MorphTargetWeights => match targets_of(node) {
                    Some(k) if k > 0 => (Property::Weights, Dimensions::Scalar, k),
                    _ => {
                        return Err(animation_err(
                            ctx,
                            &location,
                            format!(
                                "drives the morph weights of node {node}, whose mesh has no morph targets"
                            ),
                        ));
                    }
                },
            };
            let interpolation = match sampler.interpolation() {
                GltfInterpolation::Step => Interpolation::Step,
                GltfInterpolation::Linear => Interpolation::Linear,
                GltfInterpolation::CubicSpline => Interpolation::CubicSpline,
            };
            let times = read_floats(
                ctx,
                &sampler.input(),
                Dimensions::Scalar,
                &location,
                "input",
            )?;
            let values = read_floats(ctx, &sampler.output(), dims, &location, "output")?;
            if times.is_empty() {
                return Err(animation_err(
                    ctx,
                    &location,
                    "the sampler has no keys".into(),
                ));
            }
            if let Some(k) = times.iter().position(|t| !t.is_finite()) {
                return Err(animation_err(
                    ctx,
                    &location,
                    format!("key {k} is {}: key times must be finite", times[k]),
                ));
            }
            if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
                return Err(animation_err(
                    ctx,
                    &location,
                    format!(
                        "key {} ({}) does not follow key {k} ({}): key times must increase",
                        k + 1,
                        times[k + 1],
                        times[k]
                    ),
                ));
            }
            let per_key = if interpolation == Interpolation::CubicSpline {
                3
            } else {
                1
            };
            let expected = times.len() * per_key * width;
            if values.len() != expected {
                return Err(animation_err(
                    ctx,
                    &location,
                    format!(
                        "the sampler has {} keys but {} output values; {interpolation:?} needs {expected}",
                        times.len(),
                        values.len()
                    ),
                ));
            }
            if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                return Err(animation_err(
                    ctx,
                    &location,
                    format!("output value {i} is {}: values must be finite", values[i]),
                ));
            }
            duration = duration.max(times[times.len() - 1]);
            channels.push(Channel {
                node,
                property,
                interpolation,
                times,
                values,
                width,
            });
        }
        clips.push(Clip {
            name,
            duration,
            channels,
        });
    }
    Ok(clips)
}
