//! `dirt eval --quick` end to end with tiny counts: every output exists and
//! parses, and DIRT's error against brute force is 0 in every row. No timing
//! is asserted.

use std::fs;
use std::path::PathBuf;
use std::process::Command;

const DIRT: &str = env!("CARGO_BIN_EXE_dirt");

fn out_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dirt-eval-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    dir
}

fn csv_rows(path: &PathBuf) -> Vec<csv::StringRecord> {
    let mut r = csv::Reader::from_path(path).expect("open csv");
    let headers = r.headers().expect("csv header").clone();
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.expect("csv row parses")).collect();
    assert!(rows.iter().all(|x| x.len() == headers.len()));
    let mut with_header = vec![headers];
    with_header.extend(rows);
    with_header
}

fn column(rows: &[csv::StringRecord], name: &str) -> usize {
    rows[0]
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name}"))
}

#[test]
fn quick_eval_writes_parsable_outputs_with_zero_dirt_error() {
    let dir = out_dir("quick");
    let report = dir.join("RESULTS.md");
    let out = Command::new(DIRT)
        .args(["eval", "--quick", "--rays", "150", "--frames", "1", "--out"])
        .arg(&dir)
        .arg("--report")
        .arg(&report)
        .env("WGPU_BACKEND", "vulkan")
        .output()
        .expect("run dirt eval");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "dirt eval failed:\n{stderr}");

    for f in [
        "results.json",
        "builds.csv",
        "traces.csv",
        "dynamic.csv",
        "summary.md",
        "pareto_cornell.svg",
        "pareto_foliage.svg",
        "dynamic.svg",
        "renders.csv",
        "renders.svg",
        "render_reference.png",
        "leave_out.csv",
        "side.csv",
    ] {
        let p = dir.join(f);
        assert!(
            fs::metadata(&p).is_ok_and(|m| m.len() > 0),
            "{} missing",
            p.display()
        );
    }
    let json: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join("results.json")).expect("read json"))
            .expect("results.json parses");
    assert_eq!(json["rays_per_type"], 150);
    let scenes = json["scenes"].as_array().expect("scenes");
    assert_eq!(scenes.len(), 2);

    let traces = csv_rows(&dir.join("traces.csv"));
    let (backend, differ, compared, ray_type, setting) = (
        column(&traces, "backend"),
        column(&traces, "differ"),
        column(&traces, "compared"),
        column(&traces, "ray_type"),
        column(&traces, "setting"),
    );
    let dirt_rows: Vec<_> = traces[1..]
        .iter()
        .filter(|r| &r[backend] == "dirt-cpu")
        .collect();
    // 2 scenes × (5 grid points + the cost model's choice where it is not one of them)
    // × 2 traversals × 5 ray types.
    let scene = column(&traces, "scene");
    let mut points: Vec<(String, String)> = dirt_rows
        .iter()
        .map(|r| (r[scene].to_string(), r[setting].to_string()))
        .collect();
    points.sort();
    points.dedup();
    assert!((10..=12).contains(&points.len()), "{points:?}");
    assert_eq!(dirt_rows.len(), points.len() * 10);
    let choices = json["choices"].as_array().expect("choices");
    assert_eq!(choices.len(), 2);
    for c in choices {
        let (sc, st) = (
            c["scene"].as_str().expect("scene"),
            c["setting"].as_str().expect("setting"),
        );
        assert!(
            points.iter().any(|(a, b)| a == sc && b == st),
            "the choice {st} of {sc} is measured"
        );
        assert!(c["built"].as_u64().expect("built") >= 1);
    }
    for r in &dirt_rows {
        assert_eq!(&r[differ], "0", "DIRT differs from brute force: {r:?}");
        assert!(r[compared].parse::<usize>().expect("compared") > 0);
    }
    for t in ["primary", "shadow", "specular", "glossy", "diffuse"] {
        assert!(dirt_rows.iter().any(|r| &r[ray_type] == t), "no {t} rays");
    }
    assert!(dirt_rows.iter().any(|r| &r[setting] == "cube r128 B8 S1"));
    let peers: Vec<&str> = traces[1..]
        .iter()
        .map(|r| r.get(backend).unwrap_or(""))
        .collect();
    assert!(peers.contains(&"obvhs"));
    // The uniform grid shares DIRT's triangle test: held to every bit.
    let grid_rows: Vec<_> = traces[1..]
        .iter()
        .filter(|r| &r[backend] == "grid ρ4")
        .collect();
    assert_eq!(
        grid_rows.len(),
        2 * 5,
        "the grid on both scenes, every ray type"
    );
    for r in &grid_rows {
        assert_eq!(&r[differ], "0", "the grid differs from brute force: {r:?}");
    }
    assert_eq!(peers.contains(&"embree"), cfg!(feature = "embree"));
    // Side by side: both scenes against every peer in 2 alternated rounds,
    // at the cost model's choice, DIRT's hits held to every bit.
    let side = csv_rows(&dir.join("side.csv"));
    let col = |name: &str| column(&side, name);
    let mut side_peers: Vec<&str> = side[1..]
        .iter()
        .map(|r| r.get(col("peer")).unwrap_or(""))
        .collect();
    side_peers.sort_unstable();
    side_peers.dedup();
    assert!(side_peers.contains(&"obvhs"), "{side_peers:?}");
    assert_eq!(side.len() - 1, 2 * 2 * side_peers.len(), "rows of side.csv");
    for r in &side[1..] {
        let choice = choices
            .iter()
            .find(|c| c["scene"].as_str() == Some(&r[col("scene")]))
            .expect("a side row's scene has a choice");
        assert_eq!(choice["setting"].as_str(), Some(&r[col("setting")]));
        assert_eq!(
            &r[col("dirt_differ")],
            "0",
            "DIRT differs from brute force: {r:?}"
        );
        let n = |c: &str| {
            r[col(c)]
                .parse::<f64>()
                .unwrap_or_else(|_| panic!("{c}: {r:?}"))
        };
        // The peer's rounds judge the headline's rays as the headline does.
        let headline = |c: usize| -> f64 {
            traces[1..]
                .iter()
                .filter(|t| t[backend] == r[col("peer")] && t[scene] == r[col("scene")])
                .map(|t| t[c].parse::<f64>().expect("a count"))
                .sum()
        };
        assert_eq!(n("peer_differ"), headline(differ), "{r:?}");
        assert_eq!(n("peer_compared"), headline(compared), "{r:?}");
        assert!(n("peer_compared") > 0.0);
        assert_eq!(
            n("dirt_compared"),
            2.0 * n("peer_compared"),
            "both traversals"
        );
        for c in [
            "dirt_build_ms",
            "peer_build_ms",
            "dirt_linear_ms",
            "dirt_hiz_ms",
            "peer_trace_ms",
        ] {
            assert!(n(c) > 0.0, "{c}: {r:?}");
        }
        // The order is swapped every round.
        let first = &r[col("dirt_first")] == "true";
        assert_eq!(first, &r[col("round")] == "0", "{r:?}");
    }
    // The approximate methods: every setting of the quick sweep on both
    // scenes (cornell and foliage have cameras), every ray type, with the
    // error split into its kinds.
    let (other, missed, false_hits, prim) = (
        column(&traces, "other_prim"),
        column(&traces, "missed"),
        column(&traces, "false_hits"),
        column(&traces, "differ_prim"),
    );
    for (method, settings) in [("mmrt", 2), ("1-layer", 2)] {
        let rows: Vec<_> = traces[1..]
            .iter()
            .filter(|r| &r[backend] == method)
            .collect();
        assert_eq!(rows.len(), 2 * settings * 5, "{method} rows");
        for r in &rows {
            let n = |c: usize| r[c].parse::<usize>().expect("a count");
            assert_eq!(n(other) + n(missed) + n(false_hits), n(prim), "{r:?}");
        }
    }

    let dynamic = csv_rows(&dir.join("dynamic.csv"));
    let (db, dd) = (column(&dynamic, "backend"), column(&dynamic, "differ"));
    assert!(
        dynamic[1..]
            .iter()
            .any(|r| &r[db] == "dirt-cpu" && &r[dd] == "0")
    );
    // The animated assets beside the grid, DIRT exact on every frame of each.
    let ds = column(&dynamic, "scene");
    for scene in ["wave", "twister", "simple_skin", "AnimatedMorphCube"] {
        let of: Vec<_> = dynamic[1..].iter().filter(|r| &r[ds] == scene).collect();
        assert!(
            of.iter().any(|r| &r[db] == "grid ρ4" && &r[dd] == "0"),
            "no exact grid row of {scene}"
        );
        assert!(
            of.iter().any(|r| &r[db] == "dirt-cpu"),
            "no dirt-cpu row of {scene}"
        );
        assert!(
            of.iter().any(|r| &r[db] == "obvhs"),
            "no obvhs row of {scene}"
        );
        assert!(
            of.iter()
                .filter(|r| r[db].starts_with("dirt"))
                .all(|r| &r[dd] == "0"),
            "DIRT differs from brute force on {scene}"
        );
    }
    // DIRT and the renderer's BVH reference are both exact: the same images.
    let renders = csv_rows(&dir.join("renders.csv"));
    let (same, exact) = (
        column(&renders, "same_bits_as_reference_tracer"),
        column(&renders, "exact"),
    );
    assert!(renders.len() > 2);
    assert!(
        renders[1..]
            .iter()
            .filter(|r| &r[exact] == "true")
            .all(|r| &r[same] == "true")
    );
    // The approximate tracers render too (one line each in the plot).
    let tracer = column(&renders, "tracer");
    for m in ["mmrt", "1-layer"] {
        assert!(renders[1..].iter().any(|r| r[tracer].starts_with(m)), "{m}");
    }
    let builds = csv_rows(&dir.join("builds.csv"));
    assert!(builds.len() > 10);
    // Leaving out against everything on: every configuration, the same hits.
    let lo = csv_rows(&dir.join("leave_out.csv"));
    let (config, ldiff, lcmp) = (
        column(&lo, "config"),
        column(&lo, "differ"),
        column(&lo, "compared"),
    );
    for c in ["all views", "leave out", "cost model"] {
        assert!(lo[1..].iter().any(|r| &r[config] == c), "no {c} row");
    }
    for r in &lo[1..] {
        assert_eq!(&r[ldiff], "0", "leaving out changed a hit: {r:?}");
        assert!(r[lcmp].parse::<usize>().expect("compared") > 0);
    }

    let md = fs::read_to_string(&report).expect("report");
    assert!(md.contains("**DIRT: 0 rays differ**"), "{md}");
    // A dynamic frame's build is timed once, the cost model's choice in it:
    // "made in frame F's build (X ms of its Y ms" has X <= Y.
    let mut choices = 0;
    for (_, rest) in md
        .match_indices("'s build (")
        .map(|(i, _)| md.split_at(i + 10))
    {
        let mut ms = rest
            .split(" ms")
            .take(2)
            .map(|x| x.trim().trim_start_matches("of its ").parse::<f64>());
        if let (Some(Ok(choose)), Some(Ok(build))) = (ms.next(), ms.next()) {
            assert!(
                choose <= build,
                "a choice longer than its build: {rest:.80}"
            );
            choices += 1;
        }
    }
    assert!(choices > 0, "no dynamic choice noted: {md}");
    assert!(md.contains("| DIRT setting | choose ms |"), "{md}");
    // The goals, with what the run measured for those it has figures of.
    assert!(md.contains("## Speed goals"), "{md}");
    for row in [
        "| deforming grid frame (2048 triangles, rebuild + ",
        "| render cornell ",
    ] {
        assert!(md.contains(row), "no goal row {row}: {md}");
    }
    assert_eq!(
        md.contains("| trace DIRT/Embree, cornell "),
        cfg!(feature = "embree")
    );
    assert!(md.contains("The fixed setting cube r128 B8 S1"), "{md}");
    assert!(
        md.contains("## Leaving out what a scene does not need"),
        "{md}"
    );
    assert!(
        md.contains("## Error against run time: the approximate methods"),
        "{md}"
    );
    assert!(md.contains("In words: on "), "{md}");
    for f in ["knobs_mmrt.svg", "knobs_1-layer.svg"] {
        assert!(dir.join(f).exists(), "{f}");
    }
    assert!(md.contains("(results/") || md.contains("pareto_cornell.svg"));
    let _ = fs::remove_dir_all(&dir);
}

#[test]
fn eval_rejects_zero_rays() {
    let out = Command::new(DIRT)
        .args(["eval", "--quick", "--rays", "0", "--out"])
        .arg(out_dir("zero"))
        .output()
        .expect("run dirt eval");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--rays must be at least 1"));
}

#[test]
fn eval_names_a_missing_scene() {
    let out = Command::new(DIRT)
        .args(["eval", "--quick", "--scene", "/nonexistent/x.glb", "--out"])
        .arg(out_dir("missing"))
        .output()
        .expect("run dirt eval");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/nonexistent/x.glb"), "{err}");
}
