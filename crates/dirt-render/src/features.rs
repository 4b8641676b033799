//! What a render of a scene uses and what it leaves out, and why.
//!
//! Each shading feature runs only when the scene and the mode need it; this
//! module says which, so `dirt render` and `dirt info --explain` can print it.

use crate::fetch::used_textures;
use crate::lights::Lights;
use crate::{Mode, Settings};
use dirt_scene::Scene;

/// One shading feature of a render.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Feature {
    pub name: &'static str,
    /// Whether the render runs it.
    pub used: bool,
    /// Why (for a left-out feature: what in the scene or mode makes it unneeded).
    pub why: String,
}

/// The features of a render of `scene` with `settings`.
pub fn features(scene: &Scene, settings: &Settings) -> Vec<Feature> {
    let ao = settings.mode == Mode::Ao;
    let lights = Lights::new(scene);
    let used_tex = used_textures(scene).iter().filter(|u| **u).count();
    let mut out = Vec::new();
    let mut f = |name, used, why: String| out.push(Feature { name, used, why });
    f(
        "material fetch",
        !ao,
        if ao {
            "ambient occlusion reads positions and normals only".into()
        } else {
            format!("{} materials", scene.materials.len())
        },
    );
    f(
        "base-colour textures",
        !ao && used_tex > 0,
        if ao {
            "ambient occlusion needs no colour".into()
        } else if used_tex == 0 {
            format!(
                "no material of the scene's triangles has a texture ({} textures in the file)",
                scene.textures.len()
            )
        } else {
            format!(
                "{used_tex} of {} textures decoded (the ones used materials refer to)",
                scene.textures.len()
            )
        },
    );
    f(
        "shading normals",
        scene.tri_normals.is_some(),
        if scene.tri_normals.is_some() {
            "the scene has vertex normals".into()
        } else {
            "no vertex normals: the geometric normal is used".into()
        },
    );
    let nee = !ao && !lights.is_empty();
    f(
        "area-light sampling",
        nee && !lights.area.is_empty(),
        if ao {
            "ambient occlusion samples no lights".into()
        } else if lights.area.is_empty() {
            "no emissive triangles".into()
        } else {
            format!("{} emissive triangles, chosen by power", lights.area.len())
        },
    );
    f(
        "punctual lights",
        nee && !lights.punctual.is_empty(),
        if ao {
            "ambient occlusion samples no lights".into()
        } else if lights.punctual.is_empty() {
            "no KHR_lights_punctual lights".into()
        } else {
            format!(
                "{} point, spot or directional lights",
                lights.punctual.len()
            )
        },
    );
    f(
        "shadow rays (next-event estimation)",
        nee,
        if nee {
            "one per path vertex that is not a perfect mirror".into()
        } else if ao {
            "ambient occlusion traces occlusion rays instead".into()
        } else {
            "the scene has no lights: paths gather the white sky instead".into()
        },
    );
    let roulette = settings.mode == Mode::Pt && settings.russian_roulette.is_some();
    f(
        "Russian roulette",
        roulette,
        match (settings.mode, settings.russian_roulette) {
            (Mode::Pt, Some(k)) => format!("from bounce {k}"),
            (Mode::Pt, None) => "disabled: every path runs all bounces".into(),
            _ => "only path tracing continues paths".into(),
        },
    );
    out
}
