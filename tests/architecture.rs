//! Issue 34 item 5: docs/ARCHITECTURE.md's "How to add a model" held honest. A model is
//! a folder plus its line in render/registry.rs: the renderer (render/mod.rs) names no
//! model, and the single-scattering model, the one the issue asked to move as proof, is
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
