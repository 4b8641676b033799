//! `dirt render` end to end: it writes a PNG and an EXR, DIRT and the
//! reference give the same image, and bad input is an error, not a panic.

use std::fs;
use std::path::PathBuf;
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
    let run = |extra: &[&str], exr: &PathBuf| {
        let mut args = vec![
            "render",
            "--backend",
            "cpu",
            "-o",
            png.to_str().expect("utf-8"),
            "--exr",
            exr.to_str().expect("utf-8"),
        ];
        args.extend(SMALL);
        args.extend(extra);
        let out = dirt(&args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        text(&out.stderr)
    };
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
