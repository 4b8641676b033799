//! The node hierarchy: which root nodes are walked, the depth-first walk
//! composing node transforms (with cycle and instancing limits), and the
//! cameras and punctual lights (`KHR_lights_punctual`) the nodes carry.

use dirt_math::Vec3;
use glam::Mat4;

use super::Ctx;
use super::primitives::read_primitive;
use crate::SceneError;
use crate::builder::SceneBuilder;
use crate::model::{Camera, CameraKind, Light, LightKind, normal_matrix, orthonormal_up};

/// Most node visits one traversal may make (guards against exponential
/// instancing through nodes shared by several parents).
const MAX_NODE_VISITS: usize = 1 << 20;
/// The root nodes to walk: the default scene's, else scene 0's, else every
/// node that is nobody's child.
pub(super) fn root_nodes(doc: &gltf::Document, b: &mut SceneBuilder) -> Vec<usize> {
    if let Some(scene) = doc.default_scene() {
        return scene.nodes().map(|n| n.index()).collect();
    }
    let n_scenes = doc.scenes().len();
    if let Some(scene) = doc.scenes().next() {
        if n_scenes > 1 {
            b.warn(format!("no default scene; loading scene 0 of {n_scenes}"));
        }
        return scene.nodes().map(|n| n.index()).collect();
    }
    let mut is_child = vec![false; doc.nodes().len()];
    for node in doc.nodes() {
        for c in node.children() {
            if let Some(f) = is_child.get_mut(c.index()) {
                *f = true;
            }
        }
    }
    let roots: Vec<usize> = (0..is_child.len()).filter(|&i| !is_child[i]).collect();
    if !is_child.is_empty() {
        b.warn(format!("no scenes; loading all {} root nodes", roots.len()));
    }
    roots
}

enum Step {
    Enter(usize, Mat4),
    Exit(usize),
}

/// Depth-first pre-order walk with an explicit stack (no recursion, so deep
/// hierarchies cannot overflow the stack) and cycle detection.
pub(super) fn traverse(
    ctx: &mut Ctx,
    doc: &gltf::Document,
    roots: &[usize],
) -> Result<(), SceneError> {
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut on_path = vec![false; nodes.len()];
    let mut visits = 0usize;
    let mut stack: Vec<Step> = roots
        .iter()
        .rev()
        .map(|&r| Step::Enter(r, Mat4::IDENTITY))
        .collect();
    let mut warned_skin = false;

    while let Some(step) = stack.pop() {
        let (index, parent) = match step {
            Step::Exit(i) => {
                if let Some(f) = on_path.get_mut(i) {
                    *f = false;
                }
                if let Some(r) = ctx.rig.as_mut() {
                    r.path.pop();
                }
                continue;
            }
            Step::Enter(i, parent) => (i, parent),
        };
        let Some(node) = nodes.get(index) else {
            continue;
        };
        if on_path.get(index).copied().unwrap_or(false) {
            return Err(SceneError::RecursiveNodes {
                path: ctx.path.to_path_buf(),
                node: index,
            });
        }
        visits += 1;
        if visits > MAX_NODE_VISITS {
            return Err(SceneError::TooLarge {
                path: ctx.path.to_path_buf(),
                problem: format!(
                    "more than {MAX_NODE_VISITS} node instances (nodes shared by several parents?)"
                ),
            });
        }
        if let Some(f) = on_path.get_mut(index) {
            *f = true;
        }
        if let Some(r) = ctx.rig.as_mut() {
            r.path.push(index);
        }

        let global = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let label = node_label(node);
        let uses_transform =
            node.mesh().is_some() || node.camera().is_some() || node.light().is_some();
        if uses_transform && !global.is_finite() {
            return Err(SceneError::NonFiniteTransform {
                path: ctx.path.to_path_buf(),
                node: label,
            });
        }

        if let Some(mesh) = node.mesh() {
            if let Some(r) = ctx.rig.as_mut() {
                r.enter_mesh(node.skin().map(|s| s.index()), mesh.weights());
            } else if node.skin().is_some() && !warned_skin {
                warned_skin = true;
                ctx.b.warn(
                    "skinning is ignored; skinned meshes are loaded in bind pose".to_string(),
                );
            }
            let nmat = normal_matrix(global);
            let mesh_label = match mesh.name() {
                Some(n) => format!("mesh {} '{n}'", mesh.index()),
                None => format!("mesh {}", mesh.index()),
            };
            for (pi, prim) in mesh.primitives().enumerate() {
                read_primitive(
                    ctx,
                    &format!("{mesh_label} primitive {pi}"),
                    &prim,
                    global,
                    nmat,
                )?;
            }
        }
        if let Some(camera) = node.camera() {
            add_camera(ctx, &camera, global, &label);
        }
        if let Some(light) = node.light() {
            add_light(ctx, &light, global, &label);
        }

        stack.push(Step::Exit(index));
        let children: Vec<usize> = node.children().map(|c| c.index()).collect();
        stack.extend(children.into_iter().rev().map(|c| Step::Enter(c, global)));
    }
    Ok(())
}

fn node_label(node: &gltf::Node) -> String {
    match node.name() {
        Some(n) => format!("node {} '{n}'", node.index()),
        None => format!("node {}", node.index()),
    }
}

/// Node -Z as forward and +Y as up, or `None` for a degenerate transform.
pub(crate) fn node_frame(global: Mat4) -> Option<(Vec3, Vec3, Vec3)> {
    let position = global.transform_point3(Vec3::ZERO);
    let forward = global.transform_vector3(Vec3::NEG_Z).try_normalize()?;
    let (forward, up) = orthonormal_up(forward, global.transform_vector3(Vec3::Y));
    Some((position, forward, up))
}

fn add_camera(ctx: &mut Ctx, camera: &gltf::Camera, global: Mat4, label: &str) {
    let Some((position, forward, up)) = node_frame(global) else {
        ctx.b.warn(format!(
            "{label}: camera skipped, its transform is degenerate"
        ));
        return;
    };
    let name = camera.name().unwrap_or_default().to_string();
    let cam = match camera.projection() {
        gltf::camera::Projection::Perspective(p) => Camera {
            name,
            position,
            forward,
            up,
            yfov_radians: p.yfov(),
            aspect: p.aspect_ratio(),
            znear: p.znear(),
            zfar: p.zfar(),
            kind: CameraKind::Perspective,
        },
        gltf::camera::Projection::Orthographic(o) => Camera {
            name,
            position,
            forward,
            up,
            yfov_radians: 0.0,
            aspect: None,
            znear: o.znear(),
            zfar: Some(o.zfar()),
            kind: CameraKind::Orthographic {
                xmag: o.xmag(),
                ymag: o.ymag(),
            },
        },
    };
    ctx.b.scene.cameras.push(cam);
    if let Some(r) = ctx.rig.as_mut() {
        r.cameras.push(r.path.clone());
    }
}

fn add_light(ctx: &mut Ctx, light: &gltf::khr_lights_punctual::Light, global: Mat4, label: &str) {
    let Some((position, direction, _)) = node_frame(global) else {
        ctx.b.warn(format!(
            "{label}: light skipped, its transform is degenerate"
        ));
        return;
    };
    let kind = match light.kind() {
        gltf::khr_lights_punctual::Kind::Point => LightKind::Point,
        gltf::khr_lights_punctual::Kind::Directional => LightKind::Directional,
        gltf::khr_lights_punctual::Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => LightKind::Spot {
            inner_cone: inner_cone_angle,
            outer_cone: outer_cone_angle,
        },
    };
    ctx.b.scene.lights.push(Light {
        name: light.name().unwrap_or_default().to_string(),
        kind,
        position,
        direction,
        color: light.color(),
        intensity: light.intensity(),
        range: light.range(),
    });
    if let Some(r) = ctx.rig.as_mut() {
        r.lights.push(r.path.clone());
    }
}
