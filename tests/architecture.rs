//! Issue 34 item 5: docs/ARCHITECTURE.md's "How to add a model" held honest. A model is
//! a folder plus its lines in render/registry.rs: the renderer (render/mod.rs) names no
//! model and declares no model's folder, and the single-scattering model, the one the issue asked to move as proof, is
//! named nowhere outside its folder and the registry (comments aside). A special case
//! by model added anywhere else fails here, with the file and line.

use std::path::{Path, PathBuf};

/// Every .rs file under `dir`.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The code of a line: what precedes a `//` comment (string literals with `//` in them
/// are rare enough in this crate not to matter here).
fn code(line: &str) -> &str {
    line.split("//").next().unwrap_or("")
}

/// (file relative to src/, line number, line) wherever one of `needles` occurs in code,
/// outside the files `allowed` accepts.
fn occurrences(needles: &[&str], allowed: impl Fn(&str) -> bool) -> Vec<String> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut found = Vec::new();
    for f in files {
        let rel = f
            .strip_prefix(&src)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        if allowed(&rel) {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        for (i, line) in text.lines().enumerate() {
            let c = code(line);
            if needles.iter().any(|n| c.contains(n)) {
                found.push(format!("src/{rel}:{}: {}", i + 1, line.trim()));
            }
        }
    }
    found
}

#[test]
fn the_renderer_names_no_model() {
    let variants = [
        "Model::Ea",
        "Model::Refract",
        "Model::Ao",
        "Model::Single",
        "Model::Ambient",
    ];
    // The renderer: its type and frame (mod.rs), the resources models share (shared.rs),
    // the frame's target (target.rs) and the model trait (model.rs).
    let renderer = [
        "render/mod.rs",
        "render/shared.rs",
        "render/target.rs",
        "render/model.rs",
    ];
    let found = occurrences(&variants, |f| !renderer.contains(&f));
    assert!(
        found.is_empty(),
        "the renderer (render/mod.rs, shared.rs, target.rs, model.rs) must not special-case \
         a model (declare it in the model's OpticalModel instead):\n{}",
        found.join("\n")
    );
}

#[test]
fn the_single_scattering_model_lives_in_its_folder_and_the_registry() {
    let found = occurrences(&["Model::Single", "single::", "render::single"], |f| {
        f.starts_with("render/single/") || f == "render/registry.rs"
    });
    assert!(
        found.is_empty(),
        "the single-scattering model is named outside render/single/ and the registry:\n{}",
        found.join("\n")
    );
}

/// Every model is a folder `render/<name>/` declared (`mod <name>;`) in the registry
/// alone: render/mod.rs, which declares the renderer's own modules, declares no model.
#[test]
fn only_the_registry_declares_the_models_folders() {
    let render = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/render");
    for m in refrakt::render::Model::ALL {
        let name = m.name();
        assert!(
            render.join(name).join("mod.rs").is_file(),
            "model {name} has no folder src/render/{name}/"
        );
        let found = occurrences(&[&format!("mod {name};")], |f| {
            !f.starts_with("render/") || f == "render/registry.rs"
        });
        assert!(
            found.is_empty(),
            "model {name}'s folder is declared outside render/registry.rs:\n{}",
            found.join("\n")
        );
    }
}

/// A value `option` takes that is not its default (so that a value dropped on the way
/// reads back as a failure), and one it refuses.
fn other_and_refused(option: &refrakt::render::ModelOption) -> (f64, f64) {
    let d = option.default;
    let candidates = [
        d * 2.0,
        d / 2.0,
        d + 0.1,
        d - 0.1,
        1.0,
        0.5,
        2.0,
        4.0,
        10.0,
        50.0,
    ];
    let other = candidates
        .into_iter()
        .find(|&v| v != d && option.checked(v).is_ok())
        .unwrap_or_else(|| panic!("{} takes none of {candidates:?}", option.flag));
    let refused = [1e9, -1e9, 0.5, 3.0]
        .into_iter()
        .find(|&v| option.checked(v).is_err())
        .unwrap_or_else(|| panic!("{} refuses nothing", option.flag));
    (other, refused)
}

#[test]
fn every_model_option_reads_from_its_scene_key_and_is_refused_by_it() {
    use refrakt::render::declared_options;
    let options = declared_options();
    assert!(options.len() >= 5, "{} options declared", options.len());
    for (o, models) in options {
        let (other, refused) = other_and_refused(o);
        let file = |v: f64| {
            format!(
                "[volume]\nbuiltin = \"sphere\"\n[render]\nmodel = \"{}\"\n{} = {v:?}\n",
                models[0].name(),
                o.key()
            )
        };
        let path = Path::new("options.toml");
        let scene = refrakt::scene::Scene::parse(&file(other), path)
            .unwrap_or_else(|e| panic!("{} = {other}: {e:#}", o.key()));
        assert_eq!(scene.models.get(o), other, "[render] {}", o.key());
        let e = refrakt::scene::Scene::parse(&file(refused), path).unwrap_err();
        let said = format!("{e:#}");
        assert!(said.contains(&format!("[render] {}", o.key())), "{said}");
        // Given to a model that does not take it, it is refused naming the ones that do.
        if let Some(m) = refrakt::render::Model::ALL
            .into_iter()
            .find(|m| !models.contains(m))
        {
            let text = file(other).replace(
                &format!("model = \"{}\"", models[0].name()),
                &format!("model = \"{}\"", m.name()),
            );
            let e = refrakt::scene::Scene::parse(&text, path).unwrap_err();
            let said = format!("{e:#}");
            assert!(
                said.contains(&o.key()) && said.contains(models[0].name()),
                "{}: {said}",
                m.name()
            );
        }
    }
}

#[test]
fn model_options_are_written_only_in_their_declarations() {
    // The CLI, scene files and benchmarks read them from the registry: a flag or scene
    // key written as a string outside render/ is a model's option declared twice.
    for (o, _) in refrakt::render::declared_options() {
        let needles = [format!("\"{}\"", o.flag), format!("\"{}\"", o.key())];
        let needles: Vec<&str> = needles.iter().map(String::as_str).collect();
        let found = occurrences(&needles, |f| f.starts_with("render/"));
        assert!(
            found.is_empty(),
            "{} is written outside its declaration:\n{}",
            o.flag,
            found.join("\n")
        );
    }
}
