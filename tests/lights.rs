//! Issue 34 item 2: one light type for every model. A light is directional or point, with a
//! colour and a softness, in one list (the first the main light); scene files give it as
//! `[light]` or `[[light]]` tables, the command line as repeatable `--light`; the old
//! spellings (`[render] lights`, `--add-light`) still read, with a note; each model takes
//! the lights it supports and refuses more, or point lights it cannot carry, by name.

mod common;

use std::path::Path;

use glam::Vec3;
use refrakt::light::{Light, LightSource};
use refrakt::scene::Scene;

const VOLUME: &str = "[volume]\nbuiltin = \"sphere\"\nsize = 16\n";

fn lights_of(text: &str) -> anyhow::Result<Vec<Light>> {
    let scene = Scene::parse(text, Path::new("lights.toml"))?;
    Ok(scene.render_options()?.lights)
}

fn error_of(text: &str) -> String {
    format!("{:#}", lights_of(text).unwrap_err())
}

#[test]
fn light_tables_give_the_list_the_main_light_first() {
    let text = format!(
        "{VOLUME}[render]\nmodel = \"ambient\"\n\
         [[light]]\ntowards = [0.0, 1.0, 0.5]\ncolour = [2.0, 1.0, 0.5]\nsoftness = 1.5\n\
         [[light]]\nposition = [-0.8, 0.3, 0.9]\ncolour = [0.2, 0.5, 1.5]\n\
         [[light]]\ntowards = [1.0, -0.2, 0.3]\n"
    );
    let lights = lights_of(&text).unwrap();
    assert_eq!(
        lights,
        vec![
            Light {
                source: LightSource::Directional {
                    towards: Vec3::new(0.0, 1.0, 0.5)
                },
                colour: [2.0, 1.0, 0.5],
                softness: 1.5,
            },
            Light {
                source: LightSource::Point {
                    position: Vec3::new(-0.8, 0.3, 0.9)
                },
                colour: [0.2, 0.5, 1.5],
                softness: Light::DEFAULT_SOFTNESS,
            },
            Light {
                source: LightSource::Directional {
                    towards: Vec3::new(1.0, -0.2, 0.3)
                },
                colour: [1.0; 3],
                softness: Light::DEFAULT_SOFTNESS,
            },
        ]
    );
    // One [light] table is the main light alone, as it always was.
    let one = lights_of(&format!(
        "{VOLUME}[light]\ntowards = [0.0, 1.0, 0.5]\ncolour = [2.0, 1.0, 0.5]\nsoftness = 1.5\n"
    ))
    .unwrap();
    assert_eq!(one, lights[..1]);
    // The deprecated [render] lights read as the same list.
    let old = lights_of(&format!(
        "{VOLUME}[render]\nmodel = \"ambient\"\n\
         lights = [\"point:-0.8,0.3,0.9@0.2,0.5,1.5\", \"dir:1,-0.2,0.3\"]\n\
         [light]\ntowards = [0.0, 1.0, 0.5]\ncolour = [2.0, 1.0, 0.5]\nsoftness = 1.5\n"
    ))
    .unwrap();
    assert_eq!(old, lights);
}

#[test]
fn light_tables_that_make_no_sense_are_errors_that_say_which() {
    for (tables, needles) in [
        (
            "[[light]]\ntowards = [0.0, 1.0, 0.0]\nposition = [0.0, 1.0, 0.0]\n",
            &["[[light]] 1", "not both"][..],
        ),
        (
            "[[light]]\ntowards = [0.0, 1.0, 0.0]\n[[light]]\ntowards = \"env\"\n",
            &["[[light]] 2", "only the first"][..],
        ),
        (
            "[[light]]\ntowards = [0.0, 1.0, 0.0]\n[[light]]\ncolour = [1.0, 1.0, 1.0]\n",
            &["[[light]] 2", "towards", "position"][..],
        ),
        (
            "[[light]]\ntowards = [0.0, 1.0, 0.0]\n[[light]]\nposition = [0.0, 1.0, 0.0]\n\
             ambient_level = [0.1, 0.1, 0.1]\n",
            &["[[light]] 2", "ambient_level"][..],
        ),
        (
            "[[light]]\ntowards = [0.0, 1.0, 0.0]\n[[light]]\nposition = [0.0, 1.0, 0.0]\n\
             colour = [1.0, -1.0, 1.0]\n",
            &["[[light]] 2", "colour"][..],
        ),
        (
            "[[light]]\ntowards = [0.0, 1.0, 0.0]\n[[light]]\ntoward = [0.0, 1.0, 0.0]\n",
            &["[[light]] 2", "toward"][..],
        ),
        ("light = 3\n", &["[light] table", "[[light]] tables"][..]),
    ] {
        let err = error_of(&format!("{tables}{VOLUME}"));
        for n in needles {
            assert!(err.contains(n), "{tables}: expected '{n}' in: {err}");
        }
    }
}

/// Renders `sphere` at 16² with `args`; the image's pixels, or the error.
fn render(args: &[&str]) -> Result<(Vec<u8>, String), String> {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("l.png");
    let mut all = vec![
        "render",
        "sphere",
        "--volume-size",
        "16",
        "--width",
        "16",
        "--height",
        "16",
        "-o",
        out.to_str().unwrap(),
    ];
    all.extend(args);
    let o = common::refrakt(&all);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    if !o.status.success() {
        assert!(!out.exists(), "{args:?} failed and left an image");
        return Err(err);
    }
    Ok((image::open(&out).unwrap().to_rgb8().into_raw(), err))
}

#[test]
fn models_take_the_lights_they_support_and_refuse_the_rest_by_name() {
    // Ambient scattering: a point light and a directional one through repeated --light,
    // the same image as the deprecated --add-light (which says so).
    let point = "point:0.5,1,0.5@1,0.5,0.2";
    let (new, _) = render(&["--model", "ambient", "--light", "0,1,1", "--light", point]).unwrap();
    let (old, note) = render(&[
        "--model",
        "ambient",
        "--light",
        "0,1,1",
        "--add-light",
        point,
    ])
    .unwrap();
    assert_eq!(new, old, "--light twice and --add-light differ");
    assert!(note.contains("--add-light is deprecated"), "{note}");
    // The point light shines: the image differs from the main light alone.
    let (alone, _) = render(&["--model", "ambient", "--light", "0,1,1"]).unwrap();
    assert_ne!(new, alone, "the second light changed nothing");
    // A point light as the main light of the ambient model.
    render(&["--model", "ambient", "--light", point]).unwrap();

    for (args, needles) in [
        (
            &["--light", "0,1,1", "--light", "1,1,1"][..],
            &["2 lights given", "refract model takes one"][..],
        ),
        (
            &["--model", "ao", "--light", "0,1,1", "--light", "1,1,1"][..],
            &["2 lights given", "ao model takes one"][..],
        ),
        (
            &["--light", "point:0,0,3"][..],
            &[
                "point light at (0, 0, 3)",
                "refract model takes directional lights only",
            ][..],
        ),
        (
            &["--model", "single", "--light", "point:0,0,3"][..],
            &["single model takes directional lights only"][..],
        ),
        (
            &["--model", "ambient", "--light", "0,1,1", "--light", "env"][..],
            &["only the first (main) light"][..],
        ),
        (
            &[
                "--model",
                "ambient",
                "--light",
                "0,1,1",
                "--light",
                "spot:0,1,1",
            ][..],
            &["--light spot:0,1,1", "unknown kind 'spot'"][..],
        ),
        (
            &["--light", "0,1,1@1,1,1", "--light-colour", "1,0,0"][..],
            &["--light-colour"][..],
        ),
    ] {
        let err = render(args).expect_err(&format!("{args:?} rendered"));
        for n in needles {
            assert!(err.contains(n), "{args:?}: expected '{n}' in: {err}");
        }
    }
}

/// The photon tracer is the sweep's reference and takes what the sweep takes.
#[test]
fn the_photon_tracer_refuses_a_point_light() {
    let vol = refrakt::volume::procedural::sphere(8, 0.3, 1.0).unwrap();
    let tf = refrakt::transfer::TransferFunctions::default();
    let cam = refrakt::render::Camera::default();
    let mut opts = refrakt::render::RenderOptions {
        width: 8,
        height: 8,
        ..Default::default()
    };
    opts.lights = vec!["point:0,0,3".parse().unwrap()];
    let err = refrakt::photons::trace_irradiance(
        &vol,
        &tf,
        &cam,
        &opts,
        cam.distance,
        &Default::default(),
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("one directional light") && err.contains("point light at (0, 0, 3)"),
        "{err}"
    );
}

/// "How to add a kind of light" (docs/ARCHITECTURE.md) held honest. The match below has an
/// arm per `LightSource` variant, so a new kind does not compile here until it is given
/// its `--light` syntax and its `[[light]]` keys (add an example of it to `kinds` too);
/// each kind then reads from both to the same light, and every model either takes it as
/// its main light or refuses it by name.
#[test]
fn every_kind_of_light_reads_from_both_syntaxes_and_every_model_answers_it() {
    use refrakt::render::{Model, Renderer};
    let kinds = [
        LightSource::Directional {
            towards: Vec3::new(0.0, 1.0, 0.5),
        },
        LightSource::Point {
            position: Vec3::new(0.5, 1.0, 0.5),
        },
    ];
    let v = refrakt::volume::procedural::sphere(16, 0.3, 1.0).unwrap();
    let tf = common::constant_tf([0.8, 0.8, 0.8], 0.5);
    let camera = common::face_on(3.0, 30.0);
    common::with_context(|ctx| {
        let renderer = Renderer::new(ctx, &v, &tf).unwrap();
        for source in kinds {
            let (flag, keys, point) = match source {
                LightSource::Directional { towards: t } => (
                    format!("dir:{},{},{}", t.x, t.y, t.z),
                    format!("towards = [{:?}, {:?}, {:?}]", t.x, t.y, t.z),
                    false,
                ),
                LightSource::Point { position: p } => (
                    format!("point:{},{},{}", p.x, p.y, p.z),
                    format!("position = [{:?}, {:?}, {:?}]", p.x, p.y, p.z),
                    true,
                ),
            };
            let (parsed, _) = LightSource::parse_with_colour(&flag).unwrap();
            assert_eq!(parsed, source, "--light {flag}");
            let lights = lights_of(&format!("{VOLUME}[[light]]\n{keys}\n")).unwrap();
            assert_eq!(lights[0].source, source, "[[light]] {keys}");
            for model in Model::ALL {
                let mut opts = common::frame_options(32, 32, 1.0);
                opts.lights = vec![lights[0]];
                let support = model.light_support();
                let answer = renderer.check(model, &camera, &opts);
                if support.max == 0 || !point || support.point {
                    answer.unwrap_or_else(|e| panic!("{} refused {flag}: {e:#}", model.name()));
                } else {
                    let err = format!("{:#}", answer.expect_err(model.name()));
                    assert!(
                        err.contains(model.name()) && err.contains("point light"),
                        "{}: {err}",
                        model.name()
                    );
                }
            }
        }
    });
}
