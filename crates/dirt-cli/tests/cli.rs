//! The `dirt` command line end to end, on the built-in scene `cornell`.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const DIRT: &str = env!("CARGO_BIN_EXE_dirt");
const SCENE: &str = "cornell";

/// A fresh directory for one test, removed when the test passes.
struct TestDir(PathBuf);

impl TestDir {
    fn new(name: &str) -> TestDir {
        let dir = std::env::temp_dir().join(format!("dirt-cli-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).expect("create test dir");
        TestDir(dir)
    }
    fn path(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }
}

impl Drop for TestDir {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = fs::remove_dir_all(&self.0);
        }
    }
}

fn dirt(args: &[&str]) -> Output {
    Command::new(DIRT).args(args).output().expect("run dirt")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Runs dirt and requires success; returns stdout and stderr.
fn dirt_ok(args: &[&str]) -> (String, String) {
    let out = dirt(args);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(
        out.status.success(),
        "dirt {args:?} failed ({}):\n{stderr}",
        out.status
    );
    (stdout, stderr)
}

/// Runs dirt and requires failure; returns stderr.
fn dirt_err(args: &[&str]) -> String {
    let out = dirt(args);
    let stderr = text(&out.stderr);
    assert!(
        !out.status.success(),
        "dirt {args:?} should fail:\n{}{stderr}",
        text(&out.stdout)
    );
    assert_ne!(
        out.status.code(),
        Some(101),
        "dirt {args:?} panicked:\n{stderr}"
    );
    stderr
}

/// `dirt rays SCENE --out PATH --count N --seed S`.
fn write_rays(path: &Path, count: u32, seed: u32) {
    let (count, seed) = (count.to_string(), seed.to_string());
    dirt_ok(&[
        "rays",
        SCENE,
        "--out",
        s(path),
        "--count",
        &count,
        "--seed",
        &seed,
    ]);
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 temp path")
}

/// Shape and dtype descr of an .npy file.
fn npy_header(path: &Path) -> (Vec<u64>, String) {
    let bytes = fs::read(path).expect("read npy");
    let npy = npyz::NpyFile::new(&bytes[..]).expect("npy header");
    (npy.shape().to_vec(), npy.dtype().descr())
}

fn triangle_count() -> usize {
    dirt_scene::open(SCENE)
        .expect("built-in scene")
        .triangles
        .len()
}

/// An .npy file (format 1.0) written by hand: any dtype, shape, order and data.
fn raw_npy(descr: &str, shape: &[u64], fortran: bool, data: &[u8]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(u64::to_string).collect();
    let shape_text = if shape.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let order = if fortran { "True" } else { "False" };
    let mut dict =
        format!("{{'descr': '{descr}', 'fortran_order': {order}, 'shape': {shape_text}, }}");
    while (10 + dict.len() + 1) % 64 != 0 {
        dict.push(' ');
    }
    dict.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(
        &u16::try_from(dict.len())
            .expect("short header")
            .to_le_bytes(),
    );
    out.extend_from_slice(dict.as_bytes());
    out.extend_from_slice(data);
    out
}

fn rays_npy(rows: &[[f32; 8]]) -> Vec<u8> {
    let data: Vec<u8> = rows
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    raw_npy("<f4", &[rows.len() as u64, 8], false, &data)
}

/// `dirt rays`, `dirt trace --backend cpu` and `--backend brute` on the same
/// rays: the hit files must be byte-identical (DIRT's exactness claim).
#[test]
fn cpu_hits_equal_brute_force_hits_byte_for_byte() {
    let dir = TestDir::new("exact");
    let (rays, cpu, brute) = (
        dir.path("rays.npy"),
        dir.path("cpu.npy"),
        dir.path("brute.npy"),
    );
    write_rays(&rays, 20000, 7);
    assert_eq!(npy_header(&rays), (vec![20000, 8], "'<f4'".to_owned()));

    let (_, log) = dirt_ok(&[
        "trace",
        SCENE,
        "--rays",
        s(&rays),
        "--out",
        s(&cpu),
        "--backend",
        "cpu",
    ]);
    let count = format!("{} triangles", triangle_count());
    for word in [count.as_str(), "build:", "trace:", "Mrays/s", "hits:"] {
        assert!(log.contains(word), "trace log lacks {word:?}:\n{log}");
    }
    dirt_ok(&[
        "trace",
        SCENE,
        "--rays",
        s(&rays),
        "--out",
        s(&brute),
        "--backend",
        "brute",
    ]);
    assert_eq!(npy_header(&cpu), (vec![20000, 4], "'<u4'".to_owned()));

    let (a, b) = (
        fs::read(&cpu).expect("cpu hits"),
        fs::read(&brute).expect("brute hits"),
    );
    assert_eq!(a.len(), b.len());
    if a != b {
        let words = |bytes: &[u8]| -> Vec<u32> {
            let npy = npyz::NpyFile::new(bytes).expect("npy");
            npy.into_vec().expect("u32 data")
        };
        let (wa, wb) = (words(&a), words(&b));
        let differing: Vec<usize> = (0..wa.len() / 4)
            .filter(|&r| wa[4 * r..4 * r + 4] != wb[4 * r..4 * r + 4])
            .collect();
        let r = differing[0];
        panic!(
            "{} of 20000 rays differ; first row {r}: cpu {:08x?}, brute {:08x?}",
            differing.len(),
            &wa[4 * r..4 * r + 4],
            &wb[4 * r..4 * r + 4]
        );
    }

    // Some rays hit, some miss.
    let words: Vec<u32> = npyz::NpyFile::new(&a[..])
        .expect("npy")
        .into_vec()
        .expect("data");
    let hits = words.chunks_exact(4).filter(|h| h[0] != u32::MAX).count();
    assert!(hits > 1000 && hits < 20000, "{hits} hits");

    // The uniform grid shares the triangle test: the same bytes, at any density.
    for density in ["0.5", "4"] {
        let grid = dir.path(&format!("grid{density}.npy"));
        let (_, log) = dirt_ok(&[
            "trace",
            SCENE,
            "--rays",
            s(&rays),
            "--out",
            s(&grid),
            "--backend",
            "grid",
            "--density",
            density,
        ]);
        assert!(log.contains("build:") && log.contains("grid"), "{log}");
        assert!(
            fs::read(&grid).expect("grid hits") == b,
            "grid ρ{density} differs from brute force"
        );
    }
    let e = dirt_err(&[
        "trace",
        SCENE,
        "--rays",
        s(&rays),
        "--out",
        s(&brute),
        "--backend",
        "grid",
        "--density",
        "0",
    ]);
    assert!(e.contains("density"), "{e}");

    // The approximate tracers run from the command line with their knobs; they
    // say they are approximate, and most rays still find brute force's primitive.
    let prims = |bytes: &[u8]| -> Vec<u32> {
        let w: Vec<u32> = npyz::NpyFile::new(bytes)
            .expect("npy")
            .into_vec()
            .expect("data");
        w.chunks_exact(4).map(|h| h[0]).collect()
    };
    let truth = prims(&b);
    for args in [
        &["--backend", "mmrt", "--resolution", "128", "--buckets", "4"][..],
        &["--backend", "mmrt", "--thickness", "0.02", "--steps", "64"][..],
    ] {
        let out = dir.path("approx.npy");
        let mut cmd = vec!["trace", SCENE, "--rays", s(&rays), "--out", s(&out)];
        cmd.extend_from_slice(args);
        let (_, log) = dirt_ok(&cmd);
        assert!(log.contains("approximate"), "{log}");
        let got = prims(&fs::read(&out).expect("hits"));
        let same = got.iter().zip(&truth).filter(|(a, b)| a == b).count();
        assert!(
            same > got.len() / 2,
            "{args:?}: {same} of {} agree",
            got.len()
        );
    }
    // One depth layer sees only its view: it runs, and finds fewer primitives.
    let out = dir.path("layer.npy");
    let (_, log) = dirt_ok(&[
        "trace",
        SCENE,
        "--rays",
        s(&rays),
        "--out",
        s(&out),
        "--backend",
        "single-layer",
    ]);
    assert!(log.contains("approximate"), "{log}");
    let layer = fs::read(&out).expect("hits");
    assert_eq!(prims(&layer).len(), truth.len());
    // Its default walk is the depth buffer's Hi-Z: every pixel gives the same bytes.
    let linear = dir.path("layer_linear.npy");
    dirt_ok(&[
        "trace",
        SCENE,
        "--rays",
        s(&rays),
        "--out",
        s(&linear),
        "--backend",
        "single-layer",
        "--traversal",
        "linear",
    ]);
    assert!(
        fs::read(&linear).expect("hits") == layer,
        "hiz and linear differ"
    );
    let e = dirt_err(&[
        "trace",
        SCENE,
        "--rays",
        s(&rays),
        "--out",
        s(&brute),
        "--backend",
        "mmrt",
        "--thickness=-1",
    ]);
    assert!(e.contains("thickness"), "{e}");
}

#[test]
fn other_traversal_and_views_agree_with_brute_force() {
    let dir = TestDir::new("variants");
    let (rays, brute) = (dir.path("rays.npy"), dir.path("brute.npy"));
    write_rays(&rays, 3000, 11);
    dirt_ok(&[
        "trace",
        SCENE,
        "--rays",
        s(&rays),
        "--out",
        s(&brute),
        "--backend",
        "brute",
    ]);
    let truth = fs::read(&brute).expect("brute hits");
    let variants: [&[&str]; 3] = [
        &["--traversal", "hiz"],
        &[
            "--views",
            "single",
            "--resolution",
            "64",
            "--buckets",
            "4",
            "--tile",
            "2",
        ],
        &["--center", "0.3,1.2,-0.4", "--resolution", "32"],
    ];
    for (i, extra) in variants.iter().enumerate() {
        let out = dir.path(&format!("cpu{i}.npy"));
        let mut args = vec!["trace", SCENE, "--rays", s(&rays), "--out", s(&out)];
        args.extend_from_slice(extra);
        dirt_ok(&args);
        assert!(
            fs::read(&out).expect("hits") == truth,
            "{extra:?}: hits differ from brute force"
        );
    }
}

/// The independent float64 check of `tests/python/check_hits.py`, when
/// Debian's python3 with numpy is present (it must be under CI).
#[test]
fn numpy_check_accepts_the_hits() {
    let python = Path::new("/usr/bin/python3");
    let has_numpy = python.exists()
        && Command::new(python)
            .args(["-c", "import numpy"])
            .output()
            .is_ok_and(|o| o.status.success());
    if !has_numpy {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must provide /usr/bin/python3 with numpy (python3-numpy)"
        );
        eprintln!("skipped: /usr/bin/python3 with numpy not found (apt-get install python3-numpy)");
        return;
    }
    let dir = TestDir::new("numpy");
    let (tris, rays, hits) = (
        dir.path("tris.npy"),
        dir.path("rays.npy"),
        dir.path("hits.npy"),
    );
    dirt_ok(&["triangles", SCENE, "--out", s(&tris)]);
    write_rays(&rays, 5000, 13);
    dirt_ok(&["trace", SCENE, "--rays", s(&rays), "--out", s(&hits)]);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/python/check_hits.py");
    let out = Command::new(python)
        .arg(&script)
        .args([&tris, &rays, &hits])
        .output()
        .expect("run check_hits.py");
    let report = format!("{}{}", text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "check_hits.py failed:\n{report}");
    assert!(report.contains("5000 passed, 0 failed"), "{report}");
}

#[test]
fn rays_are_deterministic_for_a_seed() {
    let dir = TestDir::new("seed");
    let (a, b, c) = (dir.path("a.npy"), dir.path("b.npy"), dir.path("c.npy"));
    for kind in ["mixed", "camera", "random", "inside"] {
        dirt_ok(&[
            "rays",
            SCENE,
            "--out",
            s(&a),
            "--count",
            "500",
            "--seed",
            "1",
            "--kind",
            kind,
        ]);
        dirt_ok(&[
            "rays",
            SCENE,
            "--out",
            s(&b),
            "--count",
            "500",
            "--seed",
            "1",
            "--kind",
            kind,
        ]);
        dirt_ok(&[
            "rays",
            SCENE,
            "--out",
            s(&c),
            "--count",
            "500",
            "--seed",
            "2",
            "--kind",
            kind,
        ]);
        let (a, b, c) = (
            fs::read(&a).expect("a"),
            fs::read(&b).expect("b"),
            fs::read(&c).expect("c"),
        );
        assert!(a == b, "{kind}: same seed, different rays");
        assert!(a != c, "{kind}: different seeds, same rays");
    }
}

#[test]
fn triangles_file_has_one_row_per_triangle() {
    let dir = TestDir::new("tris");
    let out = dir.path("tris.npy");
    dirt_ok(&["triangles", SCENE, "--out", s(&out)]);
    let scene = dirt_scene::open(SCENE).expect("scene");
    assert_eq!(
        npy_header(&out),
        (vec![scene.triangles.len() as u64, 9], "'<f4'".to_owned())
    );
    let bytes = fs::read(&out).expect("read");
    let flat: Vec<f32> = npyz::NpyFile::new(&bytes[..])
        .expect("npy")
        .into_vec()
        .expect("data");
    let expected: Vec<f32> = scene
        .triangles
        .iter()
        .flat_map(|t| t.v.into_iter().flatten())
        .collect();
    assert!(
        flat.iter()
            .map(|f| f.to_bits())
            .eq(expected.iter().map(|f| f.to_bits()))
    );
}

#[test]
fn info_reports_the_triangle_count_and_the_structure() {
    let (stdout, _) = dirt_ok(&["info", SCENE]);
    let n = triangle_count();
    assert!(stdout.contains(&format!("triangles: {n}")), "{stdout}");
    for word in ["bounds:", "stats:", "memory:"] {
        assert!(stdout.contains(word), "info lacks {word:?}:\n{stdout}");
    }
    let (stdout, _) = dirt_ok(&[
        "info",
        SCENE,
        "--views",
        "single",
        "--buckets",
        "4",
        "--center",
        "0,1,0",
    ]);
    assert!(stdout.contains(&format!("triangles: {n}")), "{stdout}");
}

#[test]
fn malformed_rays_files_are_refused_with_the_reason() {
    let dir = TestDir::new("malformed");
    let hits = dir.path("hits.npy");
    let good = [0.0, 1.0, 0.5, 0.0, 0.0, 0.0, -1.0, f32::INFINITY];
    let with_bad_row = |row: usize, bad: [f32; 8]| {
        let mut rows = vec![good; 6];
        rows[row] = bad;
        rays_npy(&rows)
    };
    let f32s = |n: usize| -> Vec<u8> { (0..n).flat_map(|i| (i as f32).to_le_bytes()).collect() };
    let cases: Vec<(&str, Vec<u8>, Vec<&str>)> = vec![
        (
            "text",
            b"0 0 0 0 0 0 1 1\n".to_vec(),
            vec!["not a .npy file"],
        ),
        ("empty", Vec::new(), vec!["not a .npy file"]),
        (
            "float64",
            raw_npy("<f8", &[2, 8], false, &[0u8; 128]),
            vec!["float64", "expected float32"],
        ),
        (
            "int32",
            raw_npy("<i4", &[2, 8], false, &[0u8; 64]),
            vec!["int32", "expected float32"],
        ),
        (
            "seven",
            raw_npy("<f4", &[3, 7], false, &f32s(21)),
            vec!["(3, 7)", "expected (N, 8)"],
        ),
        (
            "flat",
            raw_npy("<f4", &[16], false, &f32s(16)),
            vec!["(16,)", "expected (N, 8)"],
        ),
        (
            "fortran",
            raw_npy("<f4", &[2, 8], true, &f32s(16)),
            vec!["Fortran order", "C order"],
        ),
        (
            "truncated",
            raw_npy("<f4", &[4, 8], false, &f32s(20)),
            vec!["truncated"],
        ),
        (
            "nan",
            with_bad_row(3, [f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0]),
            vec!["row 3:", "origin is not finite"],
        ),
        (
            "inf_dir",
            with_bad_row(4, [0.0, 0.0, 0.0, 0.0, f32::INFINITY, 0.0, 1.0, 1.0]),
            vec!["row 4:", "direction"],
        ),
        (
            "zero_dir",
            with_bad_row(5, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
            vec!["row 5:", "direction is zero"],
        ),
        (
            "tmax<tmin",
            with_bad_row(2, [0.0, 1.0, 0.0, 2.0, 0.0, 0.0, 1.0, 1.0]),
            vec!["row 2:", "tmax < tmin"],
        ),
        (
            "neg_tmin",
            with_bad_row(1, [0.0, 1.0, 0.0, -0.5, 0.0, 0.0, 1.0, 1.0]),
            vec!["row 1:", "tmin"],
        ),
        (
            "nan_tmax",
            with_bad_row(0, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, f32::NAN]),
            vec!["row 0:", "NaN"],
        ),
    ];
    for (name, bytes, words) in cases {
        let rays = dir.path(&format!("{name}.npy"));
        fs::write(&rays, bytes).expect("write rays");
        for backend in ["cpu", "brute"] {
            let stderr = dirt_err(&[
                "trace",
                SCENE,
                "--rays",
                s(&rays),
                "--out",
                s(&hits),
                "--backend",
                backend,
            ]);
            assert!(
                stderr.contains(s(&rays)),
                "{name}: message does not name the file:\n{stderr}"
            );
            for word in &words {
                assert!(
                    stderr.contains(word),
                    "{name}: message lacks {word:?}:\n{stderr}"
                );
            }
        }
    }
    assert!(!hits.exists(), "no hits file is written for bad rays");
    let missing = dir.path("missing.npy");
    let stderr = dirt_err(&["trace", SCENE, "--rays", s(&missing), "--out", s(&hits)]);
    assert!(
        stderr.contains("cannot open") && stderr.contains("missing.npy"),
        "{stderr}"
    );
}

#[test]
fn bad_arguments_are_refused_with_the_reason() {
    let stderr = dirt_err(&["info", SCENE, "--center", "1,2"]);
    assert!(stderr.contains("X,Y,Z"), "{stderr}");
    let stderr = dirt_err(&["info", SCENE, "--center", "1,two,3"]);
    assert!(stderr.contains("Y = \"two\" is not a number"), "{stderr}");
    let stderr = dirt_err(&["info", "no-such-scene"]);
    assert!(stderr.contains("no-such-scene"), "{stderr}");
    let stderr = dirt_err(&[
        "trace",
        SCENE,
        "--rays",
        "r.npy",
        "--out",
        "h.npy",
        "--backend",
        "quantum",
    ]);
    assert!(
        stderr.contains("cpu") && stderr.contains("brute"),
        "{stderr}"
    );
    let stderr = dirt_err(&["rays", SCENE, "--out", "r.npy", "--kind", "sideways"]);
    assert!(stderr.contains("mixed"), "{stderr}");
}

/// Runs dirt with extra environment variables and requires success.
fn dirt_ok_env(args: &[&str], env: &[(&str, &str)]) -> (String, String) {
    let out = Command::new(DIRT)
        .args(args)
        .envs(env.iter().copied())
        .output()
        .expect("run dirt");
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(
        out.status.success(),
        "dirt {args:?} (env {env:?}) failed ({}):\n{stderr}",
        out.status
    );
    (stdout, stderr)
}

const GPU_LINE: &str = "gpu adapter:";
const FALLBACK_LINE: &str = "falling back to the CPU backend";

/// The adapter the `dirt` binary reports on stderr, as the facts
/// `dirt_gpu::testing` decides on, or the reason it gives for using none.
fn reported_adapter(log: &str) -> Result<dirt_gpu::testing::AdapterFacts, String> {
    if let Some(line) = log.lines().find_map(|l| l.strip_prefix(GPU_LINE)) {
        let (description, path) = line.trim().rsplit_once("; ").unwrap_or((line.trim(), ""));
        return Ok(dirt_gpu::testing::AdapterFacts {
            description: description.to_owned(),
            llvmpipe: description.contains("llvmpipe"),
            exact: path.starts_with("exact"),
        });
    }
    Err(log
        .lines()
        .find(|l| l.contains(FALLBACK_LINE))
        .unwrap_or("the log names no adapter")
        .to_owned())
}

/// `dirt trace --backend gpu` writes the bytes `--backend cpu` writes: on the
/// exact path by the bit-exact contract, without an adapter because it falls
/// back to the CPU backend and says so. Whether the GPU comparison runs, is
/// skipped (and says why) or fails (`DIRT_REQUIRE_GPU=1`) is
/// `dirt_gpu::testing`'s rule for bit comparisons, applied to the adapter the
/// binary reports.
#[test]
fn gpu_hits_equal_cpu_hits_byte_for_byte() {
    let dir = TestDir::new("gpu");
    let (rays, cpu, gpu) = (
        dir.path("rays.npy"),
        dir.path("cpu.npy"),
        dir.path("gpu.npy"),
    );
    write_rays(&rays, 2000, 5);
    dirt_ok(&[
        "trace",
        SCENE,
        "--rays",
        s(&rays),
        "--out",
        s(&cpu),
        "--backend",
        "cpu",
    ]);
    let (_, log) = dirt_ok(&[
        "trace",
        SCENE,
        "--rays",
        s(&rays),
        "--out",
        s(&gpu),
        "--backend",
        "gpu",
    ]);
    let used_gpu = log.contains(GPU_LINE);
    assert!(
        used_gpu != log.contains(FALLBACK_LINE),
        "the log names the adapter or the fallback, one of them:\n{log}"
    );
    let adapter = reported_adapter(&log);
    let exact = dirt_gpu::testing::check(
        "gpu_hits_equal_cpu_hits_byte_for_byte",
        dirt_gpu::testing::Need::Exact,
        adapter.as_ref().map_err(String::as_str),
    );
    for word in ["backend gpu", "build:", "trace:", "Mrays/s", "hits:"] {
        assert!(log.contains(word), "trace log lacks {word:?}:\n{log}");
    }
    // Skipped on an adapter off the exact path; the CPU fallback's bytes are compared.
    if used_gpu && !exact {
        return;
    }
    assert!(
        fs::read(&gpu).expect("gpu hits") == fs::read(&cpu).expect("cpu hits"),
        "gpu hits differ from cpu hits:\n{log}"
    );
}

/// Without an adapter (`WGPU_BACKEND=gl`: not compiled in) `--backend gpu`
/// says so on one line and runs the CPU backend: the same bytes, status 0.
#[test]
fn gpu_backend_without_an_adapter_falls_back_to_the_cpu() {
    let dir = TestDir::new("fallback");
    let (rays, cpu, gpu) = (
        dir.path("rays.npy"),
        dir.path("cpu.npy"),
        dir.path("gpu.npy"),
    );
    dirt_ok(&["rays", SCENE, "--out", s(&rays), "--count", "500"]);
    dirt_ok(&["trace", SCENE, "--rays", s(&rays), "--out", s(&cpu)]);
    let (_, log) = dirt_ok_env(
        &[
            "trace",
            SCENE,
            "--rays",
            s(&rays),
            "--out",
            s(&gpu),
            "--backend",
            "gpu",
            "--traversal",
            "hiz",
        ],
        &[("WGPU_BACKEND", "gl")],
    );
    let fallback: Vec<&str> = log.lines().filter(|l| l.contains(FALLBACK_LINE)).collect();
    assert_eq!(fallback.len(), 1, "one fallback line:\n{log}");
    assert!(
        fallback[0].starts_with("dirt: no usable GPU ("),
        "{}",
        fallback[0]
    );
    assert!(!log.contains(GPU_LINE), "{log}");
    assert!(
        fs::read(&gpu).expect("fallback hits") == fs::read(&cpu).expect("cpu hits"),
        "fallback hits differ from cpu hits:\n{log}"
    );
}

/// `dirt bench` measures both traversals of every backend and counts the rays
/// that differ from brute force; the cpu rows must count none.
#[test]
fn bench_prints_a_table_of_both_traversals() {
    let dir = TestDir::new("bench");
    let json = dir.path("bench.json");
    let (table, log) = dirt_ok(&[
        "bench",
        SCENE,
        "--rays",
        "2000",
        "--repeat",
        "1",
        "--json",
        s(&json),
    ]);
    for word in [
        "| backend | traversal | build ms | trace ms | Mrays/s |",
        "tests/ray",
        "mismatches vs brute",
        "| linear |",
        "| hiz |",
        "| brute |",
        "2000 mixed rays",
        "CPU threads",
        "GPU: ",
    ] {
        assert!(table.contains(word), "bench table lacks {word:?}:\n{table}");
    }
    // Trace rows are `| backend | traversal | …`; the build table has no traversal.
    let rows = |backend: &str| -> Vec<String> {
        table
            .lines()
            .filter(|l| {
                ["linear", "hiz"]
                    .iter()
                    .any(|t| l.starts_with(&format!("| {backend} | {t} |")))
            })
            .map(str::to_owned)
            .collect()
    };
    let cpu_rows = rows("cpu");
    assert_eq!(cpu_rows.len(), 2, "{table}");
    for row in cpu_rows {
        assert!(
            row.contains("| 0 / 2000 |"),
            "cpu differs from brute: {row}"
        );
    }
    let gpu_used = log.contains(GPU_LINE);
    assert_eq!(
        rows("gpu").len(),
        if gpu_used { 2 } else { 0 },
        "{table}\n{log}"
    );
    // The rows are dirt_eval::measure's trace rows: `compared` and `differ`
    // count against brute force.
    let json = fs::read_to_string(&json).expect("bench json");
    for word in [
        "\"rows\"",
        "\"traversal\": \"hiz\"",
        "\"compared\": 2000",
        "\"differ\": 0",
        "\"mismatches_vs_cpu\"",
    ] {
        assert!(json.contains(word), "bench json lacks {word:?}:\n{json}");
    }
}

#[test]
fn explain_says_what_is_left_out_and_what_it_saves() {
    // From far below cornell, only the +Y face sees the box.
    let (out, _) = dirt_ok(&["info", "cornell", "--explain", "--center", "0,-30,0"]);
    for face in ["+X", "-X", "+Z", "-Z"] {
        assert!(
            out.contains(&format!(
                "view {face}: no triangle reaches any of its tiles"
            )),
            "{out}"
        );
    }
    assert!(
        out.contains("view -Y: no part of the scene bounds is in front of it"),
        "{out}"
    );
    assert!(out.contains("measured: 1 of 6 views built"), "{out}");
    assert!(out.contains("<- cheapest predicted"), "{out}");
    assert!(out.contains("<- in use"), "{out}");
    // Around the centre of the bounds every face sees geometry.
    let (out, _) = dirt_ok(&["info", "cornell", "--explain", "--resolution", "32"]);
    assert!(
        out.contains("views: none; geometry reaches every view"),
        "{out}"
    );
    assert!(out.contains("resolution 32 (given)"), "{out}");
    // The renderer's features: cornell has an emitter and no textures.
    assert!(out.contains("runs     area-light sampling"), "{out}");
    assert!(out.contains("left out base-colour textures"), "{out}");
    assert!(
        out.contains("left out material fetch: ambient occlusion"),
        "{out}"
    );
}

#[test]
fn auto_keeps_given_options_and_the_hits() {
    let dir = TestDir::new("auto");
    let rays = dir.path("rays.npy");
    write_rays(&rays, 3000, 5);
    let a = dir.path("fixed.npy");
    let b = dir.path("auto.npy");
    let c = dir.path("default.npy");
    let (_, err) = dirt_ok(&[
        "trace",
        "cornell",
        "--rays",
        s(&rays),
        "--out",
        s(&a),
        "--fixed",
    ]);
    assert!(!err.contains("ads: "), "--fixed chooses nothing: {err}");
    let (_, err) = dirt_ok(&[
        "trace",
        "cornell",
        "--rays",
        s(&rays),
        "--out",
        s(&b),
        "--auto",
        "--buckets",
        "4",
    ]);
    assert!(
        err.contains("ads: ") && err.contains(" views, resolution ") && err.contains("cost model"),
        "{err}"
    );
    assert!(err.contains(", B 4,"), "the given B is kept: {err}");
    // The default is the cost model's choice, for the rays of the file, and
    // the traversal measured faster on a sample of them.
    let (_, err) = dirt_ok(&["trace", "cornell", "--rays", s(&rays), "--out", s(&c)]);
    assert!(
        err.contains("ads: ") && err.contains("frame of 3000 rays"),
        "{err}"
    );
    assert!(
        err.contains("traversal: ") && err.contains("the faster on a sample of 3000 rays"),
        "{err}"
    );
    let d = dir.path("given.npy");
    let (_, err) = dirt_ok(&[
        "trace",
        "cornell",
        "--rays",
        s(&rays),
        "--out",
        s(&d),
        "--traversal",
        "hiz",
    ]);
    assert!(
        !err.contains("traversal: "),
        "a given traversal is not timed: {err}"
    );
    // Nothing left to choose: views, resolution and B given.
    let (_, err) = dirt_ok(&[
        "trace",
        "cornell",
        "--rays",
        s(&rays),
        "--out",
        s(&c),
        "--views",
        "cube",
        "--resolution",
        "64",
        "--buckets",
        "4",
    ]);
    assert!(!err.contains("ads: "), "{err}");
    for other in [&b, &c, &d] {
        assert_eq!(
            std::fs::read(&a).expect("read"),
            std::fs::read(other).expect("read"),
            "every choice gives the same hits"
        );
    }
    // --fixed and --auto contradict each other.
    let out = dirt(&[
        "trace",
        "cornell",
        "--rays",
        s(&rays),
        "--out",
        s(&c),
        "--fixed",
        "--auto",
    ]);
    assert!(!out.status.success());
}

// Camera rays all start at the eye: the cost model's candidates are then the
// views placed there, and the hits are still brute force's, byte for byte.
#[test]
fn camera_rays_place_the_views_at_their_origin() {
    let dir = TestDir::new("origin");
    let rays = dir.path("camera.npy");
    dirt_ok(&[
        "rays",
        "spheres",
        "--kind",
        "camera",
        "--count",
        "3000",
        "--out",
        s(&rays),
    ]);
    let (a, b) = (dir.path("placed.npy"), dir.path("brute.npy"));
    let (_, err) = dirt_ok(&["trace", "spheres", "--rays", s(&rays), "--out", s(&a)]);
    assert!(err.contains("placed at the rays' common origin"), "{err}");
    dirt_ok(&[
        "trace",
        "spheres",
        "--rays",
        s(&rays),
        "--out",
        s(&b),
        "--backend",
        "brute",
    ]);
    assert_eq!(
        std::fs::read(&a).expect("read"),
        std::fs::read(&b).expect("read")
    );
    // A given centre is kept; rays from many points are not placed.
    let mixed = dir.path("mixed.npy");
    write_rays(&mixed, 1000, 3);
    for args in [
        vec!["trace", "spheres", "--rays", s(&rays), "--center", "0,0,0"],
        vec!["trace", "spheres", "--rays", s(&mixed)],
    ] {
        let mut args = args;
        args.extend(["--out", s(&a)]);
        let (_, err) = dirt_ok(&args);
        assert!(
            err.contains("ads: ") && !err.contains("common origin"),
            "{err}"
        );
    }
}

// The evaluation's peers trace the same files, so whole processes can be
// compared. Their own triangle tests agree with brute force on the primitive
// for most rays, not all: the mixed rays aim at vertices and shared edges, where
// each test's tie rule picks its own side (76 of these 2000 for obvhs).
// Embree only where it is built in.
#[test]
fn trace_runs_the_peers_on_the_same_files() {
    let dir = TestDir::new("peers");
    let rays = dir.path("rays.npy");
    write_rays(&rays, 2000, 3);
    let brute = dir.path("brute.npy");
    let obvhs = dir.path("obvhs.npy");
    dirt_ok(&[
        "trace",
        SCENE,
        "--rays",
        s(&rays),
        "--out",
        s(&brute),
        "--backend",
        "brute",
    ]);
    let (_, err) = dirt_ok(&[
        "trace",
        SCENE,
        "--rays",
        s(&rays),
        "--out",
        s(&obvhs),
        "--backend",
        "obvhs",
    ]);
    assert!(
        err.contains("backend obvhs") && err.contains("build: "),
        "{err}"
    );
    assert!(
        !err.contains("ads: "),
        "a peer has no DIRT parameters: {err}"
    );
    let prims = |p: &Path| -> Vec<u32> {
        let bytes = fs::read(p).expect("read hits");
        let npy = npyz::NpyFile::new(&bytes[..]).expect("npy");
        let all: Vec<u32> = npy.into_vec().expect("u32 hits");
        all.chunks(4).map(|r| r[0]).collect()
    };
    let (a, b) = (prims(&brute), prims(&obvhs));
    assert_eq!(a.len(), 2000);
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert!(differ <= 200, "{differ} of 2000 rays hit another primitive");
    let embree = dir.path("embree.npy");
    let args = [
        "trace",
        SCENE,
        "--rays",
        s(&rays),
        "--out",
        s(&embree),
        "--backend",
        "embree",
    ];
    if cfg!(feature = "embree") {
        dirt_ok(&args);
        let differ = a
            .iter()
            .zip(&prims(&embree))
            .filter(|(x, y)| x != y)
            .count();
        assert!(differ <= 200, "{differ} of 2000 rays hit another primitive");
    } else {
        let err = dirt_err(&args);
        assert!(err.contains("built without the embree peer"), "{err}");
    }
}
