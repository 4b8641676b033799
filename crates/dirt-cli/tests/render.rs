//! `dirt render` end to end: it writes a PNG and an EXR, DIRT and the
//! reference give the same image, and bad input is an error, not a panic.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const DIRT: &str = env!("CARGO_BIN_EXE_dirt");

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dirt-render-cli-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    fs::create_dir_all(&d).expect("create test dir");
    d
}

fn dirt(args: &[&str]) -> Output {
    Command::new(DIRT)
        .args(args)
        // The CPU backends only: no adapter is probed.
        .output()
        .expect("run dirt")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

const SMALL: [&str; 8] = [
    "--width",
    "16",
    "--height",
    "12",
    "--spp",
    "2",
    "--bounces",
    "2",
];

/// `dirt render` with `first`, writing `png` and `exr`, at the small size,
/// then `extra`; it must succeed. Its stderr.
fn render_small(first: &[&str], png: &Path, exr: &Path, extra: &[&str]) -> String {
    let mut args = vec!["render"];
    args.extend(first);
    args.extend([
        "-o",
        png.to_str().expect("utf-8"),
        "--exr",
        exr.to_str().expect("utf-8"),
    ]);
    args.extend(SMALL);
    args.extend(extra);
    let out = dirt(&args);
    let err = text(&out.stderr);
    assert!(out.status.success(), "{args:?}: {err}");
    err
}

#[test]
fn render_writes_png_and_exr_and_backends_agree() {
    let d = dir("ok");
    let mut exrs = Vec::new();
    for backend in ["cpu", "reference"] {
        let png = d.join(format!("{backend}.png"));
        let exr = d.join(format!("{backend}.exr"));
        let mut args = vec![
            "render",
            "cornell",
            "--backend",
            backend,
            "-o",
            png.to_str().expect("utf-8"),
            "--exr",
            exr.to_str().expect("utf-8"),
        ];
        args.extend(SMALL);
        let out = dirt(&args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let err = text(&out.stderr);
        assert!(err.contains("render:") && err.contains("Mrays/s"), "{err}");
        let bytes = fs::read(&png).expect("png written");
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        let img = dirt_render::Image::read_exr(&exr).expect("exr readable");
        assert_eq!((img.width, img.height), (16, 12));
        assert!(img.pixels.iter().flatten().any(|&c| c > 0.0));
        exrs.push(fs::read(&exr).expect("exr bytes"));
    }
    assert_eq!(exrs[0], exrs[1], "DIRT and the reference differ");
    let _ = fs::remove_dir_all(&d);
}

#[test]
fn render_without_scene_uses_the_default_and_camera_overrides_work() {
    let d = dir("default");
    let a = d.join("a.exr");
    let b = d.join("b.exr");
    let png = d.join("x.png");
    let run = |extra: &[&str], exr: &PathBuf| render_small(&["--backend", "cpu"], &png, exr, extra);
    let err = run(&[], &a);
    assert!(err.contains("scene cornell"), "{err}");
    run(
        &["--eye", "0.5,1,1.5", "--target", "0,0.5,0", "--fov", "50"],
        &b,
    );
    assert_ne!(fs::read(&a).expect("a"), fs::read(&b).expect("b"));
    let _ = fs::remove_dir_all(&d);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let d = dir("bad");
    let png = d.join("x.png");
    let png = png.to_str().expect("utf-8");
    for (args, expect) in [
        (vec!["render", "-o", png, "--spp", "0"], "samples per pixel"),
        (vec!["render", "-o", png, "--width", "0"], "image size"),
        (
            vec!["render", "/no/such/scene.glb", "-o", png],
            "cannot open scene",
        ),
        (
            vec!["render", "-o", png, "--fov", "0", "--spp", "1"],
            "field of view",
        ),
        (
            vec![
                "render",
                "-o",
                "/no/such/dir/x.png",
                "--width",
                "4",
                "--height",
                "4",
                "--spp",
                "1",
            ],
            "cannot write",
        ),
        (
            vec!["render", "-o", png, "--mode", "fancy"],
            "invalid value",
        ),
    ] {
        let out = dirt(&args);
        let err = text(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(err.contains(expect), "{args:?}: {err}");
    }
    let _ = fs::remove_dir_all(&d);
}

const SKIN: &str = "/usr/share/assimp/models/glTF2/simple_skin/simple_skin.gltf";

#[test]
fn frames_are_rebuilt_written_and_previewed_and_a_lone_frame_is_the_same() {
    assert!(
        std::path::Path::new(SKIN).is_file(),
        "{SKIN} is missing: install the Debian package assimp-testmodels"
    );
    let d = dir("frames");
    let pattern = d.join("seq/frame_%03d.png");
    let mut args = vec![
        "render",
        SKIN,
        "--backend",
        "cpu",
        "--frames",
        "0..3",
        "--fps",
        "2",
        "-o",
        pattern.to_str().expect("utf-8"),
    ];
    args.extend(SMALL);
    let out = dirt(&args);
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    for n in 0..4 {
        assert!(
            err.contains(&format!("frame {n}: t {:.3} s, build ", n as f32 / 2.0)),
            "{err}"
        );
        assert!(d.join(format!("seq/frame_{n:03}.png")).is_file());
    }
    let gif = fs::read(d.join("seq/frame_preview.gif")).expect("the preview");
    assert!(gif.starts_with(b"GIF89a"));
    // The skin bends: frames differ.
    let f0 = fs::read(d.join("seq/frame_000.png")).expect("frame 0");
    let f2 = fs::read(d.join("seq/frame_002.png")).expect("frame 2");
    assert_ne!(f0, f2, "a moving scene gives different frames");

    // One process, one frame: byte for byte frame 2 of the sequence.
    let lone = d.join("lone/frame_%03d.png");
    let mut args = vec![
        "render",
        SKIN,
        "--backend",
        "cpu",
        "--frame",
        "2",
        "--fps",
        "2",
        "-o",
        lone.to_str().expect("utf-8"),
    ];
    args.extend(SMALL);
    let out = dirt(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let entries: Vec<_> = fs::read_dir(d.join("lone")).expect("lone").collect();
    assert_eq!(entries.len(), 1, "--frame writes exactly one file");
    assert_eq!(fs::read(d.join("lone/frame_002.png")).expect("lone"), f2);

    // Bad frame arguments are errors that say why.
    let png = d.join("plain.png");
    for (bad, why) in [
        (vec!["--frames", "0..2"], "no frame number pattern"),
        (vec!["--frames", "3..1"], "ends before it starts"),
        (
            vec!["--frame", "1", "--fps", "0"],
            "--fps 0 must be a positive number",
        ),
        (vec!["--frame", "1", "--animation", "4"], "names none"),
    ] {
        let mut args = vec!["render", SKIN, "-o", png.to_str().expect("utf-8")];
        args.extend(bad.iter().copied());
        args.extend(SMALL);
        let out = dirt(&args);
        assert!(!out.status.success(), "{bad:?} succeeded");
        let err = text(&out.stderr);
        assert!(err.contains(why), "{bad:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// With DIRT on the GPU, `dirt render` shades there too and says so (one
/// read-back); ambient occlusion shaded on the GPU is `--backend cpu`'s image
/// but for pixels whose one ray the GPU's rounding moved across an edge;
/// `--host-shading` shades on the CPU, and with the GPU's exact hits gives
/// `--backend cpu`'s image bit for bit.
#[test]
fn gpu_shading_from_the_command_line_agrees_with_the_cpu() {
    if dirt_gpu::testing::exact_gpu("gpu_shading_from_the_command_line_agrees_with_the_cpu")
        .is_none()
    {
        return;
    }
    let d = dir("gpu-shading");
    // The test's environment reaches the child: WGPU_BACKEND picks the adapter.
    let run = |name: &str, extra: &[&str]| {
        let exr = d.join(format!("{name}.exr"));
        let err = render_small(&["cornell"], &d.join(format!("{name}.png")), &exr, extra);
        let img = dirt_render::Image::read_exr(&exr).expect("exr readable");
        (err, img)
    };
    let (err, ao_gpu) = run("ao-gpu", &["--mode", "ao", "--backend", "gpu"]);
    assert!(
        err.contains("shaded on the GPU") && err.contains("1 read-back"),
        "{err}"
    );
    let (_, ao_cpu) = run("ao-cpu", &["--mode", "ao", "--backend", "cpu"]);
    let differ = ao_gpu
        .pixels
        .iter()
        .zip(&ao_cpu.pixels)
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        differ * 50 <= ao_gpu.pixels.len(),
        "{differ} AO pixels differ"
    );
    let (err, pt_host) = run("pt-host", &["--backend", "gpu", "--host-shading"]);
    assert!(!err.contains("shaded on the GPU"), "{err}");
    let (_, pt_cpu) = run("pt-cpu", &["--backend", "cpu"]);
    assert_eq!(pt_host.bits(), pt_cpu.bits(), "host shading of GPU hits");
    let (err, pt_gpu) = run("pt-gpu", &["--backend", "gpu"]);
    assert!(err.contains("shaded on the GPU"), "{err}");
    assert!(pt_gpu.pixels.iter().flatten().any(|&c| c > 0.0));

    // An animation: one GPU renderer for every frame, each pose rewriting its
    // tables; each frame is the host-shaded frame's to rounding.
    let frames = |name: &str, extra: &[&str]| {
        let err = render_small(
            &[SKIN, "--frames", "0..2", "--fps", "2", "--backend", "gpu"],
            &d.join(format!("{name}/f_%d.png")),
            &d.join(format!("{name}/f_%d.exr")),
            extra,
        );
        let images: Vec<dirt_render::Image> = (0..3)
            .map(|n| {
                dirt_render::Image::read_exr(&d.join(format!("{name}/f_{n}.exr")))
                    .expect("frame exr")
            })
            .collect();
        (err, images)
    };
    let (err, on_gpu) = frames("anim-gpu", &[]);
    assert_eq!(
        err.matches("the renderer kept, its scene tables rewritten")
            .count(),
        2,
        "{err}"
    );
    let (_, on_host) = frames("anim-host", &["--host-shading"]);
    assert_ne!(on_gpu[0].bits(), on_gpu[2].bits(), "the pose moved nothing");
    for (n, (g, h)) in on_gpu.iter().zip(&on_host).enumerate() {
        let (mg, mh) = (dirt_render::metrics::mean(g), dirt_render::metrics::mean(h));
        assert!(
            (mg - mh).abs() <= 0.01 * mh.abs().max(1e-3),
            "frame {n}: mean {mg} on the GPU, {mh} on the host"
        );
    }
    let _ = fs::remove_dir_all(&d);
}
