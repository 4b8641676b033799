//! Every GPU struct is declared once in Rust; these tests compare its size and
//! field offsets with the WGSL declaration as naga lays it out, and check that
//! each stage carries one name across the CPU module, the WGSL file and the GPU pass.

use std::mem::{offset_of, size_of};

/// (field name, Rust offset) in declaration order, and the Rust size.
type RustLayout = (Vec<(&'static str, usize)>, usize);

macro_rules! rust_layout {
    ($t:ty { $($f:ident),* $(,)? }) => {
        (vec![$((stringify!($f), offset_of!($t, $f))),*], size_of::<$t>())
    };
}

fn check(stage: &str, wgsl_name: &str, rust: RustLayout) {
    let module = dirt_shaders::validate(stage)
        .unwrap_or_else(|e| panic!("{stage} does not validate: {e:?}"));
    let layout = dirt_shaders::struct_layout(&module, wgsl_name)
        .unwrap_or_else(|| panic!("no struct {wgsl_name} in {stage}"));
    let (fields, size) = rust;
    assert_eq!(
        layout.size as usize, size,
        "{wgsl_name}: WGSL size {} vs Rust {size}",
        layout.size
    );
    let wgsl: Vec<(String, usize)> = layout
        .members
        .iter()
        .map(|(n, o, _)| (n.clone(), *o as usize))
        .collect();
    let rust: Vec<(String, usize)> = fields.iter().map(|(n, o)| (n.to_string(), *o)).collect();
    assert_eq!(wgsl, rust, "{wgsl_name}: members (name, offset) differ");
}

#[test]
fn shared_structs_match_their_wgsl() {
    use dirt_gpu::{
        BuildParams, FrameState, GatherParams, MipParams, PoolHeader, ScanParams, TraceParams,
        ViewsParams,
    };
    use dirt_math::{Hit, Ray, RayStats, ViewGpu};
    check(
        "trace",
        "Ray",
        rust_layout!(Ray {
            origin,
            tmin,
            dir,
            tmax
        }),
    );
    check("trace", "Hit", rust_layout!(Hit { prim, t, u, v }));
    check(
        "trace",
        "View",
        rust_layout!(ViewGpu {
            apex,
            tan,
            right,
            near,
            up,
            far,
            forward,
            eps,
            tiles,
            step,
            scale,
            slot,
            adjacency,
            ortho,
            _pad0,
            _pad1,
            _pad2
        }),
    );
    check(
        "trace",
        "RayStats",
        rust_layout!(RayStats {
            views,
            tiles,
            buckets,
            tests
        }),
    );
    check(
        "trace",
        "TraceParams",
        rust_layout!(TraceParams {
            n_rays,
            n_views,
            tiles,
            buckets,
            levels,
            traversal,
            n_slots,
            budget,
            capacity,
            with_stats,
            id_shift,
            id_capacity,
            tri_shift,
            hiz_shift,
            offset_shift,
            counted
        }),
    );
    check(
        "trace",
        "PoolHeader",
        rust_layout!(PoolHeader {
            count_in,
            count_out,
            parity,
            rounds
        }),
    );
    check(
        "fill_depth",
        "BuildParams",
        rust_layout!(BuildParams {
            n_tris,
            n_views,
            tiles,
            buckets,
            id_shift,
            tri_shift,
            hiz_shift,
            offset_shift
        }),
    );
    check(
        "mip_depth",
        "MipParams",
        rust_layout!(MipParams {
            src_base,
            dst_base,
            src_w,
            dst_w,
            shift,
            _pad0,
            _pad1,
            _pad2
        }),
    );
    check(
        "views",
        "ViewsParams",
        rust_layout!(ViewsParams {
            n_tris,
            kind,
            has_center,
            tri_shift,
            center,
            axis
        }),
    );
    check(
        "views",
        "FrameState",
        rust_layout!(FrameState { bounds, bad, reach }),
    );
    check(
        "gather",
        "GatherParams",
        rust_layout!(GatherParams {
            first_tri,
            n_tris,
            stride,
            offset,
            index_format,
            first_index,
            has_transform,
            tri_shift,
            rows
        }),
    );
    check(
        "fill_primitives",
        "ScanParams",
        rust_layout!(ScanParams {
            n,
            shift,
            _pad1,
            _pad2
        }),
    );
}

#[test]
fn the_gpu_renderers_structs_match_their_wgsl() {
    use dirt_render::gpu::types::{
        LightGpu, MaterialGpu, PathGpu, RenderParams, RenderState, ShadowGpu, SurfaceGpu,
        TextureGpu, Tone, TriGpu,
    };
    check(
        "output",
        "Tone",
        rust_layout!(Tone {
            width,
            height,
            inv_samples,
            scale
        }),
    );
    check(
        "shade",
        "RenderParams",
        rust_layout!(RenderParams {
            eye,
            tan_half_fov,
            forward,
            ortho_half_height,
            up,
            orthographic,
            right,
            offset,
            environment,
            p_area,
            seed_mix,
            width,
            height,
            n_paths,
            n_area,
            n_punctual,
            roulette_from,
            n_tris,
            n_materials,
            ao_radius,
            pad1
        }),
    );
    check(
        "shade",
        "RenderState",
        rust_layout!(RenderState {
            sample,
            bounce,
            bad_hits,
            rays,
            rays_lo,
            rays_hi,
            confirmed,
            confirmed_lo,
            confirmed_hi,
            live
        }),
    );
    check(
        "shade",
        "TriGpu",
        rust_layout!(TriGpu {
            p0,
            light_prob,
            p1,
            material,
            p2,
            has_normals,
            n0,
            has_uvs,
            n1,
            pad0,
            n2,
            pad1,
            uv0,
            uv1,
            uv2,
            pad2
        }),
    );
    check(
        "fetch",
        "MaterialGpu",
        rust_layout!(MaterialGpu {
            base,
            metallic,
            emissive,
            roughness,
            texture,
            pad0,
            pad1,
            pad2
        }),
    );
    check(
        "fetch",
        "TextureGpu",
        rust_layout!(TextureGpu {
            offset,
            width,
            height,
            pad
        }),
    );
    check(
        "shade",
        "LightGpu",
        rust_layout!(LightGpu {
            position,
            kind,
            direction,
            range,
            color,
            cos_inner,
            cos_outer,
            prim,
            area,
            cdf
        }),
    );
    check(
        "shade",
        "PathGpu",
        rust_layout!(PathGpu {
            throughput,
            alive,
            radiance,
            pdf,
            prev,
            delta,
            weight,
            scattered,
            dir,
            pad
        }),
    );
    check(
        "shade",
        "SurfaceGpu",
        rust_layout!(SurfaceGpu {
            p,
            prim,
            ng,
            front,
            ns,
            metallic,
            base,
            roughness,
            emission,
            pad
        }),
    );
    check(
        "shade",
        "ShadowGpu",
        rust_layout!(ShadowGpu { contribution, aim }),
    );
}

#[test]
fn a_changed_field_is_caught() {
    // The check has teeth: a Rust layout with two fields swapped is rejected.
    let swapped = (vec![("prim", 4usize), ("t", 0)], 16);
    let r = std::panic::catch_unwind(|| check("trace", "Hit", (swapped.0.clone(), swapped.1)));
    assert!(r.is_err());
}

#[test]
fn each_stage_has_one_name_everywhere() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let stages = dirt_shaders::STAGES.map(|s| (s, "crates/dirt-cpu/src"));
    let prepare = dirt_shaders::PREPARE_STAGES.map(|s| (s, "crates/dirt-core/src"));
    for (stage, cpu) in stages.into_iter().chain(prepare) {
        assert!(
            dirt_shaders::source(stage).is_some(),
            "shaders/wgsl/{stage}.wgsl is missing"
        );
        for dir in [cpu, "crates/dirt-gpu/src"] {
            let p = root.join(dir).join(format!("{stage}.rs"));
            assert!(p.exists(), "{} is missing", p.display());
        }
    }
    // The GPU renderer's passes carry the names of the CPU renderer's stages.
    for stage in dirt_shaders::RENDER_STAGES {
        assert!(
            dirt_shaders::source(stage).is_some(),
            "shaders/wgsl/{stage}.wgsl is missing"
        );
        let p = root
            .join("crates/dirt-render/src")
            .join(format!("{stage}.rs"));
        assert!(p.exists(), "{} is missing", p.display());
    }
}
