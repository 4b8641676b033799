//! Fully dynamic scenes: a displaced grid whose every vertex moves every
//! frame (a travelling wave), so every structure must be rebuilt each frame,
//! and beside it animated glTF assets posed by `dirt-scene` (a generated
//! skinned tube, [`twister_glb`], and the animated models of Debian's
//! `assimp-testmodels` when installed), their frames spread over their clip.
//! Per frame: rebuild + trace of the same camera rays, DIRT on the CPU (the
//! library's default, [`DirtCpu::auto`]: the cost model's choice for the frame,
//! made at the first frame's build; and the fixed cube r128 B8 S1 beside it;
//! Hi-Z traversal) and each peer, with brute force on a prefix of the rays as
//! the truth. Every tracer is measured by [`crate::measure`]. It runs once per
//! ray count of [`DynamicConfig`] and scene.

use dirt_core::{AdsParams, Tracer, Traversal};
use dirt_cpu::DirtCpu;
use dirt_math::{Ray, Triangle, Vec3};
use indicatif::ProgressBar;
use serde::Serialize;

use crate::measure::{self, Runs, StatsPass, median};
use crate::peers::{Peer, unavailable};
use crate::rays::{self, Camera, RayKind};
use crate::{EvalError, Match, compare};

/// Size of the deforming scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DynamicConfig {
    /// Quads per side: `2·grid²` triangles (the twister has as many).
    pub grid: usize,
    /// Also the animated assets: the twister and [`ANIMATED_ASSETS`].
    pub animated: bool,
    pub frames: usize,
    /// Camera rays per frame.
    pub rays: usize,
    /// A second run with this many camera rays per frame (the figure for
    /// frames with many rays), if any.
    pub rays_large: Option<usize>,
}

impl DynamicConfig {
    /// The ray counts of the runs, in order.
    pub fn ray_counts(&self) -> Vec<usize> {
        std::iter::once(self.rays).chain(self.rays_large).collect()
    }
}

/// The dynamic rows' backend name of DIRT at the fixed default setting.
pub const FIXED: &str = "dirt-cpu cube r128 B8 S1";

/// The dynamic rows' backend name of DIRT's default told where the rays start
/// (the camera's eye, [`DirtCpu::with_origin`]) and given frame 0's rays as
/// its sample ([`DirtCpu::with_sample`]).
pub const AT_CAMERA: &str = "dirt-cpu at the camera";

/// The animated models of Debian's `assimp-testmodels` measured beside the grid.
pub const ANIMATED_ASSETS: [&str; 2] = [
    "/usr/share/assimp/models/glTF2/simple_skin/simple_skin.gltf",
    "/usr/share/assimp/models/glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf",
];

/// The deforming grid's name in the rows.
pub const WAVE: &str = "wave";

/// One frame of one backend.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicRow {
    /// [`WAVE`], `twister`, or an asset's file stem.
    pub scene: String,
    pub backend: String,
    pub frame: usize,
    pub triangles: usize,
    pub rays: usize,
    pub build_ms: f64,
    pub trace_ms: f64,
    pub frame_ms: f64,
    pub compared: usize,
    pub differ: usize,
    pub differ_prim: usize,
}

/// Rays compared with brute force per frame.
const TRUTH_RAYS: usize = 500;

/// The grid at time `t`: `[-1, 1]²` in x/z, heights a travelling wave plus
/// a moving bump, so neighbouring quads tilt differently every frame.
pub fn wave_grid(n: usize, t: f32) -> Vec<Triangle> {
    let n = n.max(1);
    let h = |i: usize, j: usize| {
        let x = -1.0 + 2.0 * i as f32 / n as f32;
        let z = -1.0 + 2.0 * j as f32 / n as f32;
        let (bx, bz) = (0.6 * t.cos(), 0.6 * t.sin());
        let bump = 0.4 * (-8.0 * ((x - bx).powi(2) + (z - bz).powi(2))).exp();
        let y = 0.15 * (6.0 * x + 3.0 * t).sin() * (5.0 * z - 2.0 * t).cos() + bump;
        Vec3::new(x, y, z)
    };
    let mut tris = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (h(i, j), h(i + 1, j), h(i + 1, j + 1), h(i, j + 1));
            tris.push(Triangle::new(a, b, c));
            tris.push(Triangle::new(a, c, d));
        }
    }
    tris
}

/// The camera looking down at the grid at an angle.
fn camera() -> Option<Camera> {
    Camera::perspective(
        Vec3::new(0.0, 1.6, 2.4),
        Vec3::new(0.0, -1.5, -2.4),
        Vec3::Y,
        50f32.to_radians(),
        4.0 / 3.0,
    )
}

/// A tracer of the dynamic scene, with the name of its rows and how its hits are judged.
struct Entry {
    backend: String,
    tracer: Box<dyn Tracer>,
    how: Match,
    /// A peer: skipped (and noted once) when its library cannot do the work.
    peer: bool,
    skipped: bool,
}

/// Runs the frames for every ray count; peers that cannot start or build
/// are noted and skipped.
pub fn run(
    cfg: &DynamicConfig,
    peers: &[Peer],
    threads: usize,
    seed: u64,
    pb: &ProgressBar,
    notes: &mut Vec<String>,
) -> Result<Vec<DynamicRow>, EvalError> {
    let mut rows = Vec::new();
    let mut scenes = vec![Moving::Wave];
    if cfg.animated {
        let dir = std::env::temp_dir().join(format!("dirt-eval-twister-{}", std::process::id()));
        let twister = dir.join("twister.glb");
        std::fs::create_dir_all(&dir)
            .and_then(|()| std::fs::write(&twister, twister_glb(cfg.grid, cfg.grid)))
            .map_err(|e| EvalError::Io {
                path: twister.display().to_string(),
                source: e,
            })?;
        let loaded = dirt_scene::load_animated(&twister);
        let _ = std::fs::remove_dir_all(&dir);
        scenes.push(Moving::Asset(Box::new(loaded.map_err(|e| {
            EvalError::Scene {
                spec: "twister".into(),
                source: e,
            }
        })?)));
        for asset in ANIMATED_ASSETS {
            let path = std::path::Path::new(asset);
            if !path.is_file() {
                notes.push(format!(
                    "dynamic scenes: {asset} skipped: not found (Debian package assimp-testmodels)"
                ));
                continue;
            }
            let a = dirt_scene::load_animated(path).map_err(|e| EvalError::Scene {
                spec: asset.into(),
                source: e,
            })?;
            scenes.push(Moving::Asset(Box::new(a)));
        }
    }
    for scene in &mut scenes {
        for rays in cfg.ray_counts() {
            rows.extend(run_with(cfg, scene, rays, peers, threads, seed, pb, notes)?);
        }
    }
    Ok(rows)
}

/// A scene whose triangles change every frame.
enum Moving {
    Wave,
    Asset(Box<dirt_scene::AnimatedScene>),
}

impl Moving {
    fn name(&self) -> String {
        match self {
            Moving::Wave => WAVE.into(),
            Moving::Asset(a) => a.scene.name.clone(),
        }
    }

    /// Frame `k` of `frames`: the wave's step, or the asset posed at
    /// `k / (frames - 1)` of its clip.
    fn frame(&mut self, grid: usize, k: usize, frames: usize) -> Result<Vec<Triangle>, EvalError> {
        match self {
            Moving::Wave => Ok(wave_grid(grid, 0.35 * k as f32)),
            Moving::Asset(a) => {
                let t = a.duration() * k as f32 / frames.saturating_sub(1).max(1) as f32;
                a.pose(t).map_err(|e| EvalError::Scene {
                    spec: a.scene.name.clone(),
                    source: e,
                })?;
                Ok(a.scene.triangles.clone())
            }
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn run_with(
    cfg: &DynamicConfig,
    scene: &mut Moving,
    ray_count: usize,
    peers: &[Peer],
    threads: usize,
    seed: u64,
    pb: &ProgressBar,
    notes: &mut Vec<String>,
) -> Result<Vec<DynamicRow>, EvalError> {
    let name = scene.name();
    let dirt = |backend: &str, tracer: DirtCpu| Entry {
        backend: backend.into(),
        tracer: Box::new(tracer),
        how: Match::Bits,
        peer: false,
        skipped: false,
    };
    let mut entries = vec![
        dirt("dirt-cpu", DirtCpu::auto(None, ray_count as u64)),
        dirt(FIXED, DirtCpu::new(AdsParams::default(), Traversal::HiZ)),
    ];
    for peer in peers {
        match (peer.make)(threads) {
            Ok(tracer) => entries.push(Entry {
                backend: peer.name.into(),
                tracer,
                how: peer.how(),
                peer: true,
                skipped: false,
            }),
            Err(e) if unavailable(&e) => notes.push(format!("dynamic scene {name}: {e}")),
            Err(source) => return Err(build_err(&name, source)),
        }
    }
    let mut rows = Vec::new();
    // An asset's camera frames its first pose and stays.
    let mut cam = match scene {
        Moving::Wave => camera(),
        Moving::Asset(_) => None,
    };
    for frame in 0..cfg.frames {
        let tris = scene.frame(cfg.grid, frame, cfg.frames)?;
        if cam.is_none() {
            let b = dirt_math::Aabb::of_triangles(&tris);
            cam = Some(Camera::in_front_of(&b, b.extent().length().max(1e-3)));
        }
        let rays: Vec<Ray> = rays::generate(&tris, cam, RayKind::Camera, ray_count, seed)?;
        if frame == 0
            && let Some(c) = cam
        {
            // An application knows its camera: the default told so, beside the default.
            let t = DirtCpu::auto(None, ray_count as u64)
                .with_origin(c.eye)
                .with_sample(&rays);
            entries.insert(1, dirt(AT_CAMERA, t));
        }
        let n = TRUTH_RAYS.min(rays.len());
        let truth = dirt_cpu::brute_force::trace(&tris, &rays[..n]);
        for e in entries.iter_mut().filter(|e| !e.skipped) {
            let built = measure::build(e.tracer.as_mut(), &tris, Runs::Once);
            let built = match built {
                Ok(b) => b,
                Err(err) if e.peer && unavailable(&err) => {
                    notes.push(format!("dynamic scene {name}: {err}"));
                    e.skipped = true;
                    continue;
                }
                Err(source) => return Err(build_err(&name, source)),
            };
            let traced = measure::trace(e.tracer.as_mut(), &rays, Runs::Once, StatsPass::Prefix(0))
                .map_err(|source| EvalError::Trace {
                    scene: name.clone(),
                    source,
                })?;
            let d = compare(&traced.hits, &truth, e.how);
            if let Some(ms) = built.stage("choose") {
                notes.push(format!(
                    "dynamic scene {name}, {} rays per frame: {} is the cost model's choice, made in frame {frame}'s build ({} ms of its {} ms; later frames keep it unless the rays begin or stop sharing an origin)",
                    rays.len(),
                    e.tracer.name(),
                    format_ms(ms),
                    format_ms(built.build_ms)
                ));
            }
            rows.push(DynamicRow {
                scene: name.clone(),
                backend: e.backend.clone(),
                frame,
                triangles: tris.len(),
                rays: rays.len(),
                build_ms: built.build_ms,
                trace_ms: traced.trace_ms,
                frame_ms: built.build_ms + traced.trace_ms,
                compared: d.compared,
                differ: d.differ,
                differ_prim: d.differ_prim,
            });
        }
        pb.inc(1);
    }
    Ok(rows)
}

/// A skinned tube as a GLB file: `rings × segments × 2` triangles around the
/// y axis from 0 to 2, weighted from a base joint to a top joint (pivot at
/// y = 1) across the middle, and a 4 s clip in which the base turns a full
/// circle about y while the top bends 60° one way and the other (LINEAR
/// rotation keys). Every vertex above the base moves every frame.
pub fn twister_glb(rings: usize, segments: usize) -> Vec<u8> {
    let (rings, segments) = (rings.max(1), segments.max(3));
    let mut positions = Vec::new();
    let mut joints: Vec<u16> = Vec::new();
    let mut weights = Vec::new();
    for r in 0..=rings {
        let y = 2.0 * r as f32 / rings as f32;
        let w1 = (y - 0.5).clamp(0.0, 1.0);
        for k in 0..segments {
            let a = std::f32::consts::TAU * k as f32 / segments as f32;
            positions.extend([0.3 * a.cos(), y, 0.3 * a.sin()]);
            joints.extend([0, 1, 0, 0]);
            weights.extend([1.0 - w1, w1, 0.0, 0.0]);
        }
    }
    let mut indices: Vec<u32> = Vec::new();
    for r in 0..rings {
        for k in 0..segments {
            let i = |r: usize, k: usize| (r * segments + k % segments) as u32;
            let (a, b, c, d) = (i(r, k), i(r, k + 1), i(r + 1, k + 1), i(r + 1, k));
            indices.extend([a, c, b, a, d, c]);
        }
    }
    let ibm: [f32; 32] = [
        1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., //
        1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., -1., 0., 1.,
    ];
    let times = [0.0f32, 1.0, 2.0, 3.0, 4.0];
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let base: [f32; 20] = [
        0., 0., 0., 1., 0., h, 0., h, 0., 1., 0., 0., 0., h, 0., -h, 0., 0., 0., -1.,
    ];
    let axis = glam::Vec3::new(1.0, 0.0, 1.0).normalize();
    let top: Vec<f32> = [0.0f32, 60.0, 0.0, -60.0, 0.0]
        .iter()
        .flat_map(|d| glam::Quat::from_axis_angle(axis, d.to_radians()).to_array())
        .collect();

    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut add = |bytes: Vec<u8>, accessor: serde_json::Value| {
        let offset = bin.len();
        bin.extend(&bytes);
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        views.push(
            serde_json::json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}),
        );
        let mut a = accessor;
        a["bufferView"] = serde_json::json!(views.len() - 1);
        accessors.push(a);
        accessors.len() - 1
    };
    let f32s = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let vertices = (rings + 1) * segments;
    let pos = add(
        f32s(&positions),
        serde_json::json!({"componentType": 5126, "count": vertices, "type": "VEC3",
            "min": [-0.3, 0.0, -0.3], "max": [0.3, 2.0, 0.3]}),
    );
    let jnt = add(
        joints.iter().flat_map(|x| x.to_le_bytes()).collect(),
        serde_json::json!({"componentType": 5123, "count": vertices, "type": "VEC4"}),
    );
    let wgt = add(
        f32s(&weights),
        serde_json::json!({"componentType": 5126, "count": vertices, "type": "VEC4"}),
    );
    let idx = add(
        indices.iter().flat_map(|x| x.to_le_bytes()).collect(),
        serde_json::json!({"componentType": 5125, "count": indices.len(), "type": "SCALAR"}),
    );
    let ibm = add(
        f32s(&ibm),
        serde_json::json!({"componentType": 5126, "count": 2, "type": "MAT4"}),
    );
    let input = add(
        f32s(&times),
        serde_json::json!({"componentType": 5126, "count": 5, "type": "SCALAR", "min": [0.0], "max": [4.0]}),
    );
    let base = add(
        f32s(&base),
        serde_json::json!({"componentType": 5126, "count": 5, "type": "VEC4"}),
    );
    let top = add(
        f32s(&top),
        serde_json::json!({"componentType": 5126, "count": 5, "type": "VEC4"}),
    );
    let json = serde_json::json!({
        "asset": {"version": "2.0", "generator": "dirt-eval twister"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "tube", "mesh": 0, "skin": 0},
            {"name": "base", "children": [2]},
            {"name": "top", "translation": [0.0, 1.0, 0.0]}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "JOINTS_0": jnt, "WEIGHTS_0": wgt}, "indices": idx}]}],
        "skins": [{"joints": [1, 2], "inverseBindMatrices": ibm}],
        "animations": [{"name": "twist", "channels": [
            {"sampler": 0, "target": {"node": 1, "path": "rotation"}},
            {"sampler": 1, "target": {"node": 2, "path": "rotation"}}
        ], "samplers": [
            {"input": input, "output": base, "interpolation": "LINEAR"},
            {"input": input, "output": top, "interpolation": "LINEAR"}
        ]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors
    });
    let mut j = json.to_string().into_bytes();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let total = 12 + 8 + j.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(j);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// Milliseconds with at most three decimals (trailing zeros dropped).
fn format_ms(ms: f64) -> String {
    format!("{ms:.3}")
        .trim_end_matches('0')
        .trim_end_matches('.')
        .to_string()
}

fn build_err(scene: &str, source: dirt_core::CoreError) -> EvalError {
    EvalError::Build {
        scene: scene.into(),
        source,
    }
}

/// Median per-frame figures of one backend: `(build, trace, frame)` in ms
/// (`rows` of one scene and ray count).
pub fn medians(rows: &[DynamicRow], backend: &str) -> Option<(f64, f64, f64)> {
    let of: Vec<&DynamicRow> = rows.iter().filter(|r| r.backend == backend).collect();
    if of.is_empty() {
        return None;
    }
    Some((
        median(of.iter().map(|r| r.build_ms).collect()),
        median(of.iter().map(|r| r.trace_ms).collect()),
        median(of.iter().map(|r| r.frame_ms).collect()),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_moves_every_vertex_between_frames() {
        let a = wave_grid(8, 0.0);
        let b = wave_grid(8, 0.35);
        assert_eq!(a.len(), 128);
        assert_eq!(b.len(), 128);
        let moved = a
            .iter()
            .zip(&b)
            .filter(|(x, y)| (0..3).any(|k| x.vertex(k) != y.vertex(k)))
            .count();
        assert_eq!(moved, 128);
        assert!(a.iter().all(Triangle::is_finite));
    }

    #[test]
    fn the_twister_loads_bends_and_keeps_its_base() {
        let dir = tempfile_dir();
        let p = dir.join("twister.glb");
        std::fs::write(&p, twister_glb(8, 6)).unwrap_or_else(|e| panic!("{e}"));
        let mut a = dirt_scene::load_animated(&p).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(a.scene.len(), 8 * 6 * 2);
        assert!(a.is_animated());
        assert_eq!(a.duration(), 4.0);
        let rest = a.scene.triangles.clone();
        // At t = 1 the base has turned 90° about y and the top bent 60°.
        a.pose(1.0).unwrap_or_else(|e| panic!("{e}"));
        let posed = &a.scene.triangles;
        // Base vertices (y = 0, weight on the base joint only) turn about y:
        // (x, 0, z) -> (z, 0, -x).
        let v = rest[0].vertex(0);
        assert_eq!(v.y, 0.0);
        let w = posed[0].vertex(0);
        assert!(
            (w - glam::Vec3::new(v.z, 0.0, -v.x)).length() < 1e-5,
            "{v} -> {w}"
        );
        let top_moved = rest
            .iter()
            .zip(posed)
            .filter(|(r, p)| r.vertex(2).y > 1.9 && (r.vertex(2) - p.vertex(2)).length() > 0.1)
            .count();
        assert!(top_moved > 0, "the top bends");
        let _ = std::fs::remove_dir_all(&dir);
    }

    fn tempfile_dir() -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("dirt-eval-twister-test-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap_or_else(|e| panic!("{e}"));
        d
    }
}
