//! Scenes that move: a glTF file's animations evaluated at a time.
//!
//! [`AnimatedScene`] holds a [`Scene`] and, for a glTF file with animations,
//! skins or morph targets, what it takes to pose it again: every node's rest
//! transform, the animation clips (node translation, rotation and scale
//! channels, morph target weights; STEP, LINEAR and CUBICSPLINE samplers),
//! the skins (joints and inverse bind matrices) and, per mesh primitive, its
//! object-space vertices, morph target deltas, joints and weights and the
//! triangles it made. [`AnimatedScene::pose`] writes the triangles, normals,
//! cameras and lights at time `t` into the scene in place (the flattened
//! order and every other attribute stay as loaded), reusing its allocations.
//!
//! The evaluation follows the glTF 2.0 specification:
//! * a node's local transform is `T * R * S` of its (animated) translation,
//!   rotation and scale; nodes no channel of the clip targets keep the
//!   matrix the static loader uses, so their triangles have the same bits;
//! * before a sampler's first key its first value holds, after the last key
//!   its last value; LINEAR rotations are slerped (shortest arc) and every
//!   rotation is normalised;
//! * a vertex is `base + Σ wᵢ·targetᵢ` (positions and normals) with the
//!   node's animated weights, else the node's, else the mesh's defaults,
//!   else zero;
//! * a skinned vertex is `Σ wⱼ · (global(jointⱼ) · inverseBindⱼ) · p` (four
//!   influences, `JOINTS_0`/`WEIGHTS_0`, weights normalised to sum to one);
//!   the skinned mesh node's own transform is ignored, as the specification
//!   requires. Normals use the inverse-transpose of the same matrix.

use std::path::{Path, PathBuf};

use dirt_math::{Triangle, Vec3};
use glam::{Mat4, Quat};

use crate::builder::face_normal;
use crate::model::normal_matrix;
use crate::{Scene, SceneError};

/// A scene and what it takes to pose it at a time.
#[derive(Clone, Debug)]
pub struct AnimatedScene {
    /// The scene as last posed (at load: time 0 of clip 0, or the rest pose
    /// of a scene without a rig).
    pub scene: Scene,
    rig: Option<Rig>,
    clip: usize,
    time: f32,
}

/// One animation of a glTF file.
#[derive(Clone, Debug, PartialEq)]
pub struct ClipInfo {
    /// The animation's name (empty when the file gives none).
    pub name: String,
    /// Its last key time in seconds.
    pub duration: f32,
    /// How many channels it has.
    pub channels: usize,
}

impl AnimatedScene {
    /// A scene that does not move (a built-in, an OBJ file, a glTF file
    /// without animations, skins or morph targets).
    pub fn fixed(scene: Scene) -> Self {
        Self {
            scene,
            rig: None,
            clip: 0,
            time: 0.0,
        }
    }

    pub(crate) fn rigged(scene: Scene, rig: Rig) -> Result<Self, SceneError> {
        let mut s = Self {
            scene,
            rig: Some(rig),
            clip: 0,
            time: 0.0,
        };
        s.pose(0.0)?;
        Ok(s)
    }

    /// The file's animations, in file order.
    pub fn clips(&self) -> Vec<ClipInfo> {
        self.rig.as_ref().map_or_else(Vec::new, |r| {
            r.clips
                .iter()
                .map(|c| ClipInfo {
                    name: c.name.clone(),
                    duration: c.duration,
                    channels: c.channels.len(),
                })
                .collect()
        })
    }

    /// The clip [`pose`](Self::pose) plays (0 unless chosen).
    pub fn clip(&self) -> usize {
        self.clip
    }

    /// Chooses the clip [`pose`](Self::pose) plays; `false` (and no change)
    /// when there is no clip `index`.
    pub fn set_clip(&mut self, index: usize) -> bool {
        let n = self.rig.as_ref().map_or(0, |r| r.clips.len());
        if index < n {
            self.clip = index;
        }
        index < n
    }

    /// Whether posing at different times can move anything: the scene has a
    /// clip with at least one channel.
    pub fn is_animated(&self) -> bool {
        self.rig
            .as_ref()
            .and_then(|r| r.clips.get(self.clip))
            .is_some_and(|c| !c.channels.is_empty())
    }

    /// The chosen clip's duration in seconds (0 for a scene that does not move).
    pub fn duration(&self) -> f32 {
        self.rig
            .as_ref()
            .and_then(|r| r.clips.get(self.clip))
            .map_or(0.0, |c| c.duration)
    }

    /// The time of the last pose.
    pub fn time(&self) -> f32 {
        self.time
    }

    /// Poses the scene at time `t` seconds of the chosen clip: triangles,
    /// normals, cameras and lights are rewritten in place. A scene without a
    /// rig is left as it is. Times outside the clip hold its first or last
    /// keys (loop by passing `t % duration()`).
    pub fn pose(&mut self, t: f32) -> Result<(), SceneError> {
        let Some(rig) = self.rig.as_mut() else {
            return Ok(());
        };
        if !t.is_finite() {
            return Err(rig.err("pose", format!("time {t} is not finite")));
        }
        rig.pose(self.clip, t, &mut self.scene)?;
        self.time = t;
        Ok(())
    }
}

/// Opens a scene that may move: like [`open`](crate::open), but a glTF file
/// keeps its animations, skins and morph targets (see [`AnimatedScene`]).
pub fn open_animated(spec: &str) -> Result<AnimatedScene, SceneError> {
    let path = Path::new(spec);
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if crate::builtin(spec).is_none() && matches!(ext.as_str(), "gltf" | "glb") {
        return load_animated(path);
    }
    crate::open(spec).map(AnimatedScene::fixed)
}

/// Loads a glTF file with its animations, skins and morph targets, posed at
/// time 0 of its first clip. Never panics (as [`load`](crate::load)).
pub fn load_animated(path: &Path) -> Result<AnimatedScene, SceneError> {
    crate::catch_panics(path, || crate::gltf_loader::load_gltf_animated(path))
}

/// [`load_animated`] from a glTF's bytes in memory (a `.glb`, or a `.gltf`
/// whose buffers and images are `data:` URIs), as a web page gets a dropped
/// file: nothing is read from disk, and an external URI is an error.
/// `name` names the scene and stands for the path in errors.
pub fn load_animated_bytes(name: &str, bytes: Vec<u8>) -> Result<AnimatedScene, SceneError> {
    crate::catch_panics(Path::new(name), || {
        crate::gltf_loader::load_gltf_bytes(name, bytes, true)
    })
}

/// A node's property a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Property {
    Translation,
    Rotation,
    Scale,
    Weights,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Interpolation {
    Step,
    Linear,
    CubicSpline,
}

/// One channel with its sampler's keys and values (`width` floats each; a
/// cubic spline stores in-tangent, value, out-tangent per key).
#[derive(Clone, Debug)]
pub(crate) struct Channel {
    pub node: usize,
    pub property: Property,
    pub interpolation: Interpolation,
    pub times: Vec<f32>,
    pub values: Vec<f32>,
    pub width: usize,
}

impl Channel {
    /// The element `k` of the values (`part` 1 is the value of a cubic key).
    fn element(&self, k: usize, part: usize) -> &[f32] {
        let i = match self.interpolation {
            Interpolation::CubicSpline => 3 * k + part,
            _ => k,
        };
        self.values
            .get(i * self.width..(i + 1) * self.width)
            .unwrap_or(&[])
    }

    /// The channel's value at `t` into `out` (`width` floats).
    pub fn sample(&self, t: f32, out: &mut Vec<f32>) {
        out.clear();
        let n = self.times.len();
        let (first, last) = match (self.times.first(), self.times.last()) {
            (Some(&a), Some(&b)) => (a, b),
            _ => return,
        };
        if n == 1 || t <= first {
            out.extend_from_slice(self.element(0, 1));
        } else if t >= last {
            out.extend_from_slice(self.element(n - 1, 1));
        } else {
            // times[k] <= t < times[k + 1]
            let k = self.times.partition_point(|&x| x <= t).saturating_sub(1);
            let (t0, t1) = (self.times[k], self.times[k + 1]);
            let td = t1 - t0;
            let s = (t - t0) / td;
            match self.interpolation {
                Interpolation::Step => out.extend_from_slice(self.element(k, 1)),
                Interpolation::Linear if self.property == Property::Rotation => {
                    let q0 = quat(self.element(k, 1));
                    let q1 = quat(self.element(k + 1, 1));
                    out.extend_from_slice(&q0.slerp(q1, s).to_array());
                }
                Interpolation::Linear => {
                    let (a, b) = (self.element(k, 1), self.element(k + 1, 1));
                    out.extend(a.iter().zip(b).map(|(&a, &b)| a + s * (b - a)));
                }
                Interpolation::CubicSpline => {
                    let (s2, s3) = (s * s, s * s * s);
                    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                    let h10 = td * (s3 - 2.0 * s2 + s);
                    let h01 = -2.0 * s3 + 3.0 * s2;
                    let h11 = td * (s3 - s2);
                    let (v0, b0) = (self.element(k, 1), self.element(k, 2));
                    let (a1, v1) = (self.element(k + 1, 0), self.element(k + 1, 1));
                    out.extend(
                        (0..self.width)
                            .map(|i| h00 * v0[i] + h10 * b0[i] + h01 * v1[i] + h11 * a1[i]),
                    );
                }
            }
        }
        if self.property == Property::Rotation && out.len() == 4 {
            let q = quat(out).normalize();
            out.clear();
            out.extend_from_slice(&q.to_array());
        }
    }
}

fn quat(v: &[f32]) -> Quat {
    match v {
        &[x, y, z, w] => Quat::from_xyzw(x, y, z, w),
        _ => Quat::IDENTITY,
    }
}

#[derive(Clone, Debug)]
pub(crate) struct Clip {
    pub name: String,
    pub duration: f32,
    pub channels: Vec<Channel>,
}

/// A node's rest state.
#[derive(Clone, Debug)]
pub(crate) struct Node {
    /// The local matrix the static loader composes (bit for bit).
    pub matrix: Mat4,
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
    pub parent: Option<usize>,
    /// The node's default morph weights, if it gives any.
    pub weights: Option<Vec<f32>>,
}

/// A mesh reached through one path of nodes (a node instanced twice is two instances).
#[derive(Clone, Debug)]
pub(crate) struct Instance {
    /// Node indices from a root to the node that holds the mesh.
    pub path: Vec<usize>,
    pub skin: Option<usize>,
    /// The mesh's default morph weights.
    pub weights: Vec<f32>,
}

#[derive(Clone, Debug)]
pub(crate) struct Skin {
    pub joints: Vec<usize>,
    pub inverse_bind: Vec<Mat4>,
}

/// One morph target's deltas (absent attributes are `None`).
#[derive(Clone, Debug)]
pub(crate) struct Target {
    pub positions: Option<Vec<Vec3>>,
    pub normals: Option<Vec<Vec3>>,
}

/// Four joints (indices into a skin's joints) and their weights.
pub(crate) type Influence = ([u32; 4], [f32; 4]);

/// One primitive of one instance and the triangles it made.
#[derive(Clone, Debug)]
pub(crate) struct Primitive {
    pub instance: usize,
    pub location: String,
    /// Its first triangle in the flattened order.
    pub first: usize,
    /// Vertex indices of each of its triangles.
    pub corners: Vec<[u32; 3]>,
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub targets: Vec<Target>,
    /// Per vertex: four joints (indices into the skin's joints) and their
    /// weights, normalised.
    pub influences: Option<Vec<Influence>>,
}

/// Everything that poses a loaded glTF scene.
#[derive(Clone, Debug)]
pub(crate) struct Rig {
    pub path: PathBuf,
    pub nodes: Vec<Node>,
    pub instances: Vec<Instance>,
    pub primitives: Vec<Primitive>,
    pub skins: Vec<Skin>,
    pub clips: Vec<Clip>,
    /// Node paths of the scene's cameras and lights, in their order.
    pub cameras: Vec<Vec<usize>>,
    pub lights: Vec<Vec<usize>>,
    // Scratch, kept between poses.
    locals: Vec<Mat4>,
    globals: Vec<Option<Mat4>>,
    weights: Vec<Option<Vec<f32>>>,
    world: Vec<Vec3>,
    world_normals: Vec<Vec3>,
}

impl Rig {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        path: PathBuf,
        nodes: Vec<Node>,
        instances: Vec<Instance>,
        primitives: Vec<Primitive>,
        skins: Vec<Skin>,
        clips: Vec<Clip>,
        cameras: Vec<Vec<usize>>,
        lights: Vec<Vec<usize>>,
    ) -> Self {
        Self {
            path,
            nodes,
            instances,
            primitives,
            skins,
            clips,
            cameras,
            lights,
            locals: Vec::new(),
            globals: Vec::new(),
            weights: Vec::new(),
            world: Vec::new(),
            world_normals: Vec::new(),
        }
    }

    fn err(&self, location: &str, problem: String) -> SceneError {
        SceneError::Animation {
            path: self.path.clone(),
            location: location.to_string(),
            problem,
        }
    }

    /// Local matrices and morph weights of every node at `t`.
    fn sample(&mut self, clip: usize, t: f32) {
        let n = self.nodes.len();
        self.locals.clear();
        self.locals.extend(self.nodes.iter().map(|n| n.matrix));
        self.weights.clear();
        self.weights.resize(n, None);
        let Some(clip) = self.clips.get(clip) else {
            return;
        };
        let mut trs: Vec<Option<(Vec3, Quat, Vec3)>> = vec![None; n];
        let mut value = Vec::new();
        for c in &clip.channels {
            let Some(node) = self.nodes.get(c.node) else {
                continue;
            };
            c.sample(t, &mut value);
            if c.property == Property::Weights {
                self.weights[c.node] = Some(value.clone());
                continue;
            }
            let (tr, rot, sc) =
                trs[c.node].get_or_insert((node.translation, node.rotation, node.scale));
            match (c.property, value.as_slice()) {
                (Property::Translation, &[x, y, z]) => *tr = Vec3::new(x, y, z),
                (Property::Scale, &[x, y, z]) => *sc = Vec3::new(x, y, z),
                (Property::Rotation, v) => *rot = quat(v),
                _ => {}
            }
        }
        for (i, x) in trs.into_iter().enumerate() {
            if let Some((tr, rot, sc)) = x {
                self.locals[i] = Mat4::from_scale_rotation_translation(sc, rot, tr);
            }
        }
    }

    /// The global matrix of `node` through its parents.
    fn global(&mut self, node: usize) -> Result<Mat4, SceneError> {
        let mut chain = Vec::new();
        let mut at = Some(node);
        let mut base = Mat4::IDENTITY;
        while let Some(i) = at {
            if let Some(Some(g)) = self.globals.get(i) {
                base = *g;
                break;
            }
            if chain.len() > self.nodes.len() {
                return Err(SceneError::RecursiveNodes {
                    path: self.path.clone(),
                    node,
                });
            }
            chain.push(i);
            at = self.nodes.get(i).and_then(|n| n.parent);
        }
        for &i in chain.iter().rev() {
            base *= self.locals[i];
            self.globals[i] = Some(base);
        }
        Ok(base)
    }

    fn path_global(&self, path: &[usize]) -> Mat4 {
        path.iter().fold(Mat4::IDENTITY, |g, &i| g * self.locals[i])
    }

    fn pose(&mut self, clip: usize, t: f32, scene: &mut Scene) -> Result<(), SceneError> {
        self.sample(clip, t);
        self.globals.clear();
        self.globals.resize(self.nodes.len(), None);
        // Joint matrices of every skin.
        let mut joint_mats: Vec<Vec<Mat4>> = Vec::with_capacity(self.skins.len());
        for s in 0..self.skins.len() {
            let mut mats = Vec::with_capacity(self.skins[s].joints.len());
            for j in 0..self.skins[s].joints.len() {
                let g = self.global(self.skins[s].joints[j])?;
                let ibm = self.skins[s]
                    .inverse_bind
                    .get(j)
                    .copied()
                    .unwrap_or(Mat4::IDENTITY);
                mats.push(g * ibm);
            }
            joint_mats.push(mats);
        }
        let mut world = std::mem::take(&mut self.world);
        let mut world_normals = std::mem::take(&mut self.world_normals);
        let result = (|| {
            for p in &self.primitives {
                self.pose_primitive(p, t, &joint_mats, &mut world, &mut world_normals, scene)?;
            }
            Ok(())
        })();
        self.world = world;
        self.world_normals = world_normals;
        result?;
        for (i, path) in self.cameras.iter().enumerate() {
            let g = self.path_global(path);
            if let (Some(c), Some((position, forward, up))) =
                (scene.cameras.get_mut(i), crate::gltf_loader::node_frame(g))
            {
                (c.position, c.forward, c.up) = (position, forward, up);
            }
        }
        for (i, path) in self.lights.iter().enumerate() {
            let g = self.path_global(path);
            if let (Some(l), Some((position, direction, _))) =
                (scene.lights.get_mut(i), crate::gltf_loader::node_frame(g))
            {
                (l.position, l.direction) = (position, direction);
            }
        }
        Ok(())
    }

    fn pose_primitive(
        &self,
        p: &Primitive,
        t: f32,
        joint_mats: &[Vec<Mat4>],
        world: &mut Vec<Vec3>,
        world_normals: &mut Vec<Vec3>,
        scene: &mut Scene,
    ) -> Result<(), SceneError> {
        let Some(inst) = self.instances.get(p.instance) else {
            return Ok(());
        };
        let node = inst.path.last().copied().unwrap_or(0);
        // Morph weights: animated, else the node's, else the mesh's.
        let weights: &[f32] = match (self.weights.get(node), self.nodes.get(node)) {
            (Some(Some(w)), _) => w,
            (
                _,
                Some(Node {
                    weights: Some(w), ..
                }),
            ) => w,
            _ => &inst.weights,
        };
        let global = self.path_global(&inst.path);
        let global_nmat = normal_matrix(global);
        let skin = inst.skin.and_then(|s| joint_mats.get(s));
        world.clear();
        world_normals.clear();
        for (v, &base) in p.positions.iter().enumerate() {
            let mut pos = base;
            let mut nrm = p.normals.as_ref().map(|ns| ns[v]);
            for (target, &w) in p.targets.iter().zip(weights) {
                if w == 0.0 {
                    continue;
                }
                if let Some(d) = &target.positions {
                    pos += w * d[v];
                }
                if let (Some(n), Some(d)) = (nrm.as_mut(), &target.normals) {
                    *n += w * d[v];
                }
            }
            let m = match (skin, &p.influences) {
                (Some(mats), Some(inf)) => {
                    let (joints, ws) = inf[v];
                    let mut m = Mat4::ZERO;
                    for (&j, &w) in joints.iter().zip(&ws) {
                        if w != 0.0 {
                            m += mats.get(j as usize).copied().unwrap_or(Mat4::IDENTITY) * w;
                        }
                    }
                    m
                }
                _ => global,
            };
            let wp = m.transform_point3(pos);
            if !wp.is_finite() {
                return Err(self.err(
                    &p.location,
                    format!("vertex {v} posed at time {t} is not finite: {wp}"),
                ));
            }
            world.push(wp);
            if let Some(n) = nrm {
                let wn = if skin.is_some() {
                    normal_matrix(m) * n
                } else {
                    global_nmat * n
                };
                world_normals.push(wn.normalize_or_zero());
            }
        }
        for (k, c) in p.corners.iter().enumerate() {
            let Some(tri) = scene.triangles.get_mut(p.first + k) else {
                continue;
            };
            let at = |i: u32| world.get(i as usize).copied().unwrap_or(Vec3::ZERO);
            *tri = Triangle::new(at(c[0]), at(c[1]), at(c[2]));
            let face = face_normal(tri);
            if let Some(ns) = scene.tri_normals.as_mut()
                && let Some(out) = ns.get_mut(p.first + k)
            {
                *out = c.map(|i| match world_normals.get(i as usize) {
                    Some(&n) if n != Vec3::ZERO && n.is_finite() => n.to_array(),
                    _ => face.to_array(),
                });
            }
        }
        Ok(())
    }
}
