//! Issue 17 item 5: `refrakt bench models`, every model of `Model::ALL` after the protocol
//! of Table 1 of Ament et al. ("Ambient Volume Scattering"). Times are never compared with
//! fixed numbers: the runs are checked for structure (every model, in order), for what is
//! known independently of the timings (ratios recomputed from the reported frames, which
//! changes apply to which model, a change that must rebuild something), for the paper's
//! figures as Table 1 prints them, and for clean errors.

mod common;

use std::path::Path;

use refrakt::bench::{ModelsReport, MODELS_SCHEMA};
use refrakt::render::Model;

fn refrakt(args: &[&str]) -> std::process::Output {
    common::refrakt_command(args)
        // The same private stand-in cache as tests/bench.rs.
        .env(
            "REFRAKT_CACHE_DIR",
            std::env::temp_dir().join("refrakt-bench-test-cache"),
        )
        .output()
        .expect("running refrakt")
}

/// A small ambient-scattering table (albedo 0.9, seconds to build), written once per test
/// process, so `bench models` does not build the default one (a minute) into the cache.
fn small_ambient_table() -> String {
    static PATH: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    PATH.get_or_init(|| {
        let path = std::env::temp_dir().join(format!(
            "refrakt-bench-models-table-{}.bin",
            std::process::id()
        ));
        let p = path.to_str().unwrap().to_string();
        let o = refrakt(&[
            "precompute",
            "ambient",
            "--theta-bins",
            "9",
            "--extinction-bins",
            "12",
            "--g-bins",
            "5",
            "--paths",
            "64",
            "--out",
            &p,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        p
    })
    .clone()
}

fn text(o: &std::process::Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        (s[n / 2 - 1] + s[n / 2]) / 2.0
    }
}

fn read(path: &Path) -> ModelsReport {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The models the bench times: all but the experimental ones (the eikonal model).
fn names() -> Vec<&'static str> {
    let benched: Vec<&str> = Model::benched().iter().map(|m| m.name()).collect();
    assert!(benched.contains(&"refract") && !benched.contains(&"eikonal"));
    benched
}

#[test]
fn every_model_is_timed_with_its_ratio_to_ea_and_its_change_costs() {
    let dir = tempfile::tempdir().unwrap();
    // An empty data folder: the stand-in is used and the lung scan is missing.
    let data = dir.path().join("data");
    std::fs::create_dir(&data).unwrap();
    let json = dir.path().join("m.json");
    let csv = dir.path().join("m.csv");
    let svg = dir.path().join("m.svg");
    let (frames, warmup) = (2usize, 1usize);
    let o = refrakt(&[
        "bench",
        "models",
        "--scale",
        "0.05",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--rows",
        "kiwi,lung-ct",
        "--data-dir",
        data.to_str().unwrap(),
        "--quiet",
        "--ambient-table",
        &small_ambient_table(),
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("early ray termination at α = 0.98"),
        "{stdout}"
    );
    assert!(
        stdout.contains("| Kiwi | 13×13×6 (stand-in) | ea |"),
        "{stdout}"
    );
    assert!(
        stdout.contains("- lung-ct: ") && stdout.contains("lung1_image.nrrd not found"),
        "the missing scan must be reported: {stdout}"
    );
    // The paper's table as a reference, whatever the rows.
    assert!(
        stdout.contains("| Vis. Human | 202 × 256 × 259 |"),
        "{stdout}"
    );
    // The eikonal model is experimental: timed only when --models names it.
    assert!(!stdout.contains("Ihrke"), "{stdout}");

    let r = read(&json);
    assert_eq!(r.schema, MODELS_SCHEMA);
    assert_eq!((r.settings.frames, r.settings.warmup), (2, 1));
    assert_eq!(r.settings.viewport, 26);
    assert_eq!(r.settings.termination_alpha, 0.98);
    assert_eq!(r.settings.models, names());
    assert_eq!(r.settings.ratio_to, "ea");
    assert_eq!(r.settings.rows, ["kiwi"]);
    assert_eq!(r.skipped.len(), 1);
    assert_eq!(r.skipped[0].dataset, "lung-ct");
    assert!(
        r.skipped[0].reason.contains("fetch-data"),
        "{:?}",
        r.skipped
    );

    assert_eq!(r.rows.len(), 1);
    let row = &r.rows[0];
    assert_eq!((row.dataset.as_str(), row.viewport), ("kiwi", [26, 26]));
    assert!(
        row.paper.is_empty(),
        "only the supernova row has the paper's figures"
    );
    let got: Vec<&str> = row.models.iter().map(|m| m.model.as_str()).collect();
    assert_eq!(got, names(), "every model of Model::benched, in order");
    let ea = row.models.iter().find(|m| m.model == "ea").unwrap();
    let ea_median = median(&ea.frames_ms);
    assert_eq!(ea.ratio_to_ea, 1.0);
    for (m, model) in row.models.iter().zip(Model::benched()) {
        assert_eq!(
            (m.frames_ms.len(), m.warmup_ms.len()),
            (frames, warmup),
            "{}",
            m.model
        );
        assert!(m.frames_ms.iter().all(|t| *t > 0.0), "{}", m.model);
        assert!(
            (m.stats.median - median(&m.frames_ms)).abs() < 1e-9,
            "{}",
            m.model
        );
        let ratio = median(&m.frames_ms) / ea_median;
        assert!((m.ratio_to_ea - ratio).abs() < 1e-12, "{}", m.model);
        assert!(m.paper.is_none(), "{}", m.model);
        // Which changes apply follows the model's capabilities.
        let tf = m.tf_change.as_ref().expect("every model has a TF");
        assert_eq!(m.ls_change.is_some(), model.uses_light(), "{}", m.model);
        if !model.has_phase_function() {
            assert!(m.pf_change.is_none(), "{}", m.model);
        }
        // A change's cost is the sum of the scopes it lists, each a rebuild scope.
        for c in [Some(tf), m.ls_change.as_ref(), m.pf_change.as_ref()]
            .into_iter()
            .flatten()
        {
            let sum: f64 = c.scopes.iter().map(|s| s.ms).sum();
            assert!((c.ms - sum).abs() < 1e-9, "{}", m.model);
            assert!(c.ms >= 0.0 && c.ms.is_sign_positive(), "{}", m.model);
            for s in &c.scopes {
                assert!(
                    r.settings.rebuild_scopes.contains(&s.scope),
                    "{}: {}",
                    m.model,
                    s.scope
                );
            }
        }
    }
    // AO's occlusion comes from the extinction volume's SAT, which a TF change rebuilds.
    let ao = row.models.iter().find(|m| m.model == "ao").unwrap();
    let tf = ao.tf_change.as_ref().unwrap();
    assert!(tf.ms > 0.0, "{tf:?}");
    assert!(
        tf.scopes.iter().any(|s| s.scope == "sat3d" && s.ms > 0.0),
        "{tf:?}"
    );
    assert!(ea.ls_change.is_none(), "EA does not use the light");
    // Single scattering caches the light's transmittance: a light change rebuilds it; its
    // phase function is evaluated per sample, so a phase change rebuilds nothing.
    let single = row.models.iter().find(|m| m.model == "single").unwrap();
    let ls = single.ls_change.as_ref().unwrap();
    assert!(
        ls.scopes
            .iter()
            .any(|s| s.scope == "transmittance cache" && s.ms > 0.0),
        "{ls:?}"
    );
    let pf = single.pf_change.as_ref().unwrap();
    assert_eq!(pf.ms, 0.0, "{pf:?}");
    assert!(stdout.contains("n/a"), "{stdout}");

    // CSV: a header, then per model every frame and one record per applicable change.
    let per_model: usize = row
        .models
        .iter()
        .map(|m| {
            warmup
                + frames
                + [&m.tf_change, &m.ls_change, &m.pf_change]
                    .iter()
                    .filter(|c| c.is_some())
                    .count()
        })
        .sum();
    let csv_text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(csv_text.lines().count(), 1 + per_model, "{csv_text}");
    assert!(csv_text
        .lines()
        .skip(1)
        .all(|l| l.starts_with(MODELS_SCHEMA)));
    assert!(csv_text.contains(",ao,tf-change,"), "{csv_text}");
    assert!(!csv_text.contains(",ea,ls-change,"), "{csv_text}");

    let svg_text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        svg_text.contains("<svg") && svg_text.contains("Kiwi"),
        "svg"
    );
}

/// `bench models` at scale 0.05, one frame, no warm-up, on `rows`, with the `extra`
/// arguments and an empty data folder: the report and stdout (the run must succeed).
fn one_frame_run(rows: &str, extra: &[&str]) -> (ModelsReport, String) {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    std::fs::create_dir(&data).unwrap();
    let json = dir.path().join("m.json");
    let mut args = vec![
        "bench",
        "models",
        "--scale",
        "0.05",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--rows",
        rows,
        "--data-dir",
        data.to_str().unwrap(),
        "--quiet",
        "--json",
        json.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = refrakt(&args);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    (read(&json), stdout)
}

#[test]
fn the_supernova_row_carries_the_papers_figures() {
    let table = small_ambient_table();
    let (r, stdout) = one_frame_run("supernova", &["--ambient-table", &table]);
    assert!(r.skipped.is_empty(), "{:?}", r.skipped);
    let row = &r.rows[0];
    assert_eq!(row.dataset, "supernova");
    // Table 1, Supernova: TF -/532/490 ms, PF -/-/34, LS -/-/34, 64/27/20 fps.
    type Figures<'a> = (&'a str, Option<f64>, Option<f64>, Option<f64>, f64);
    let paper: Vec<Figures> = row
        .paper
        .iter()
        .map(|p| {
            (
                p.model.as_str(),
                p.tf_change_ms,
                p.pf_change_ms,
                p.ls_change_ms,
                p.fps,
            )
        })
        .collect();
    assert_eq!(
        paper,
        [
            ("emission-absorption", None, None, None, 64.0),
            ("ambient occlusion", Some(532.0), None, None, 27.0),
            (
                "ambient scattering",
                Some(490.0),
                Some(34.0),
                Some(34.0),
                20.0
            ),
        ]
    );
    for p in &row.paper {
        assert!((p.ms - 1000.0 / p.fps).abs() < 1e-9, "{}", p.model);
    }
    let ratios: Vec<f64> = row.paper.iter().map(|p| p.ratio).collect();
    assert_eq!(ratios, [1.0, 2.4, 3.2]);
    // Beside ours: EA and AO have the paper's figures, a model the paper lacks has none.
    for m in &row.models {
        match m.model.as_str() {
            "ea" => assert_eq!(m.paper.as_ref().unwrap().fps, 64.0),
            "ao" => assert_eq!(m.paper.as_ref().unwrap().tf_change_ms, Some(532.0)),
            "refract" => assert!(m.paper.is_none()),
            _ => {}
        }
    }
    assert!(
        stdout.contains("| 15.6 | 1.0 | - | - | - |"),
        "EA's paper figures: {stdout}"
    );
    // The paper's ambient scattering is beside ours now.
    let ambient = row.models.iter().find(|m| m.model == "ambient").unwrap();
    assert_eq!(ambient.paper.as_ref().unwrap().tf_change_ms, Some(490.0));
}

#[test]
fn bad_rows_and_scale_are_clean_errors() {
    let o = refrakt(&["bench", "models", "--rows", "kiwi,teapot", "--quiet"]);
    let (_, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("--rows") && stderr.contains("teapot") && stderr.contains("mri-head"),
        "{stderr}"
    );
    for scale in ["0", "-1", "nan"] {
        let o = refrakt(&["bench", "models", "--scale", scale, "--quiet"]);
        let (_, stderr) = text(&o);
        assert_eq!(o.status.code(), Some(1), "{scale}: {stderr}");
        assert!(
            stderr.contains("--scale") && stderr.contains("must be a number in (0, 4]"),
            "{scale}: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    let o = refrakt(&["bench", "models", "--svg", "chart.png", "--quiet"]);
    let (_, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("--svg") && stderr.contains(".svg"),
        "{stderr}"
    );
}

#[test]
fn help_explains_the_protocol() {
    let o = refrakt(&["bench", "models", "--help"]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stderr}");
    for needle in [
        "Table 1",
        "512²",
        "0.98",
        "lung-ct",
        "skipped",
        "opacity × 0.999",
        "refrakt-bench-models/1",
    ] {
        assert!(stdout.contains(needle), "{needle}: {stdout}");
    }
}

/// Issue 35 item 6: `--models` names the models to time, the experimental eikonal model
/// among them (EA is always timed: the ratios' base). The eikonal model's light update is
/// its LS change: the simulation runs again when the light turns (and when the transfer
/// function changes), while a change of g reruns nothing (the view reads g per frame);
/// Eikonal Rendering's own figures are printed beside ours. Unknown names are clean
/// errors that list the models.
#[test]
fn the_eikonal_model_is_timed_when_named_with_its_light_update() {
    // No --ambient-table: the ambient model is not timed, so none is loaded or built.
    let (r, stdout) = one_frame_run("kiwi", &["--models", "eikonal"]);
    assert_eq!(r.settings.models, ["ea", "eikonal"]);
    let row = &r.rows[0];
    let names: Vec<&str> = row.models.iter().map(|m| m.model.as_str()).collect();
    assert_eq!(names, ["ea", "eikonal"]);
    let eikonal = &row.models[1];
    let simulated = |c: &Option<refrakt::bench::Change>, what: &str| {
        let c = c.as_ref().unwrap_or_else(|| panic!("{what}: n/a"));
        let sim = c.scopes.iter().find(|s| s.scope == "light simulation");
        assert!(
            sim.is_some_and(|s| s.ms > 0.0),
            "{what} must run the light simulation again: {c:?}"
        );
    };
    simulated(&eikonal.ls_change, "the light change");
    simulated(&eikonal.tf_change, "the transfer-function change");
    let pf = eikonal.pf_change.as_ref().expect("the eikonal model has g");
    assert_eq!(pf.ms, 0.0, "a change of g rebuilt {:?}", pf.scopes);
    assert!(
        stdout.contains("| Kiwi | 13×13×6 (stand-in) | eikonal |"),
        "{stdout}"
    );
    assert!(
        stdout.contains("GeForce 8800 GTX") && stdout.contains("5 to 10 s"),
        "Eikonal Rendering's figures must be beside ours: {stdout}"
    );

    let o = refrakt(&["bench", "models", "--models", "ea,teapot", "--quiet"]);
    let (_, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("--models") && stderr.contains("teapot") && stderr.contains("eikonal"),
        "{stderr}"
    );
}
