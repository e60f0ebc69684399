//! A scene file's tables resolved into a [`Scene`]: relative paths against the file,
//! each section into [`Overrides`] applied by [`Scene::apply`], the settings that do not
//! apply to the file's model refused (`model_settings`), the models' options checked once
//! the model is known to take them.

use super::*;

impl SceneFile {
    /// The settings this file gives that belong to some models (or to the forward light
    /// transport) only, by their command-line flags, for
    /// [`super::refuse_what_does_not_apply`].
    fn model_settings(&self) -> Vec<Given> {
        let mut given = Vec::new();
        let mut add = |flag: &'static str, written: String| given.push(Given { flag, written });
        let light_keys: Vec<(String, String)> = match &self.light {
            Some(toml::Value::Table(t)) => {
                t.keys().map(|k| ("[light]".into(), k.clone())).collect()
            }
            Some(toml::Value::Array(a)) => a
                .iter()
                .filter_map(|t| t.as_table())
                .flat_map(|t| t.keys().map(|k| ("[[light]]".into(), k.clone())))
                .collect(),
            _ => Vec::new(),
        };
        for (table, key) in light_keys {
            // A light table describes a light (its softness and colour too, which models
            // that take lights but do not soften them leave as they are); the ambient
            // level is the frame's, as --ambient-level.
            let flag = match key.as_str() {
                "towards" | "position" | "colour" | "softness" => "--light",
                "ambient_level" => "--ambient-level",
                _ => continue,
            };
            add(flag, format!("{table} {key}"));
        }
        if let Some(e) = &self.environment {
            if e.map.is_some() {
                add("--env", "[environment] map".into());
            }
            if e.rotation.is_some() {
                add("--env-rotation", "[environment] rotation".into());
            }
        }
        if let Some(RenderSection { table: r, models }) = &self.render {
            for (key, _) in models {
                if let Some(o) = find_option(key) {
                    add(o.flag, format!("[render] {key}"));
                }
            }
            for (flag, key, set) in [
                ("--roughness", "roughness", r.roughness.is_some()),
                ("--specular", "specular", r.specular.is_some()),
                ("--eta-scale", "eta_scale", r.eta_scale.is_some()),
                (
                    "--light-transport",
                    "light_transport",
                    r.light_transport.is_some(),
                ),
                ("--light-rays", "light_rays", r.light_rays.is_some()),
                (
                    "--light-spacing",
                    "light_spacing",
                    r.light_spacing.is_some(),
                ),
                ("--reflections", "reflections", r.reflections.is_some()),
                ("--clip", "clip", r.clip.is_some()),
                ("--light", "lights", r.lights.is_some()),
            ] {
                if set {
                    add(flag, format!("[render] {key}"));
                }
            }
        }
        given
    }

    pub(in crate::scene) fn resolve(self, path: &Path) -> Result<Scene> {
        let given = self.model_settings();
        let base = path.parent().unwrap_or(Path::new("."));
        let rel = |p: &str| -> Result<PathBuf> {
            let q = base.join(p);
            ensure!(q.exists(), "{}: referenced file not found", q.display());
            Ok(q)
        };
        let v = &self.volume;
        let mut s = match (&v.file, &v.builtin) {
            (Some(_), Some(_)) => bail!("[volume]: give either file or builtin, not both"),
            (None, None) => bail!("[volume]: needs file = \"...\" or builtin = \"...\""),
            (None, Some(b)) => {
                let mut s = Scene::builtin(b)?.with_context(|| {
                    let names: Vec<String> = builtin_names().into_iter().map(|(n, _)| n).collect();
                    format!("[volume] builtin '{b}' is not one of {}", names.join(", "))
                })?;
                match &mut s.volume {
                    VolumeSource::Procedural { size, .. } => {
                        if let Some(n) = v.size {
                            *size = n;
                        }
                        ensure!(v.scale.is_none(), "[volume] scale is for thesis stand-ins");
                    }
                    VolumeSource::Standin { scale, .. } => {
                        if let Some(f) = v.scale {
                            *scale = f;
                        }
                        ensure!(
                            v.size.is_none(),
                            "[volume] size is for procedural volumes; stand-ins take scale"
                        );
                    }
                    _ => ensure!(
                        v.size.is_none() && v.scale.is_none(),
                        "[volume] size/scale apply to procedural volumes and stand-ins only"
                    ),
                }
                s
            }
            (Some(f), None) => {
                let file = rel(f)?;
                let raw = match (v.dims, &v.kind) {
                    (Some(dims), Some(k)) => Some(crate::volume::formats::RawLayout {
                        dims,
                        kind: parse_scalar_kind(k)?,
                        spacing: v.spacing,
                    }),
                    (None, None) => None,
                    _ => bail!("[volume] raw files need both dims and type"),
                };
                let mut s = Scene::for_volume_file(&file);
                s.volume = VolumeSource::File {
                    path: file,
                    raw,
                    window: None,
                };
                s
            }
        };
        if let Some(w) = v.window {
            ensure!(
                w[0].is_finite() && w[1].is_finite() && w[0] < w[1],
                "[volume] window {w:?} must be two finite numbers, low < high"
            );
            match &mut s.volume {
                VolumeSource::File { window, .. } | VolumeSource::Fetched { window, .. } => {
                    *window = Some((w[0], w[1]))
                }
                _ => bail!("[volume] window applies to volume files only"),
            }
        }
        if let Some(sp) = v.spacing {
            ensure!(
                sp.iter().all(|x| x.is_finite() && *x > 0.0),
                "[volume] spacing {sp:?} must be three finite positive numbers"
            );
        }
        s.spacing = v.spacing;
        s.file = Some(path.to_path_buf());
        let mut o = Overrides::default();
        if let Some(f) = &v.flip {
            o.flip = Some(parse_flip(f).context("[volume] flip")?);
        }
        ensure!(
            v.upright.is_none()
                || matches!(
                    s.volume,
                    VolumeSource::File { .. } | VolumeSource::Fetched { .. }
                ),
            "[volume] upright applies to volume files and scans, not built-in scenes"
        );
        o.upright = v.upright;
        if let Some(l) = &v.labels {
            o.labels = Some(match LabelChoice::parse(l) {
                LabelChoice::Table(p) => LabelChoice::Table(rel(&p.to_string_lossy())?),
                other => other,
            });
        }
        if let Some(code) = &v.orientation {
            o.orientation =
                Some(crate::volume::orientation::parse_code(code).context("[volume] orientation")?);
        }
        if let Some(spec) = &v.rotate {
            o.rotate =
                Some(crate::volume::orientation::parse_rotation(spec).context("[volume] rotate")?);
        }
        if let Some(n) = self.name {
            // The name is printed with every render: bounded, one line.
            let chars = n.chars().count();
            ensure!(
                chars <= 200,
                "name: {chars} characters; at most 200 (it is printed with every render)"
            );
            ensure!(
                !n.chars().any(char::is_control),
                "name: control characters (a line break, a tab, NUL) are not allowed"
            );
            s.name = n;
        } else if let Some(stem) = path.file_stem() {
            s.name = stem.to_string_lossy().into_owned();
        }
        if let Some(t) = self.transfer {
            let inline =
                t.colour.is_some() || t.opacity.is_some() || t.medium.is_some() || t.eta.is_some();
            let count = t.preset.is_some() as u32 + t.file.is_some() as u32 + inline as u32;
            ensure!(
                count <= 1,
                "[transfer]: give one of preset, file, or inline functions"
            );
            if let Some(p) = t.preset {
                TransferFunctions::load(&p)
                    .map_err(|_| anyhow::anyhow!("[transfer] preset '{p}' does not exist"))?;
                o.transfer = Some(TransferSource::Named(p));
            } else if let Some(f) = t.file {
                let p = rel(&f)?;
                o.transfer = Some(TransferSource::Named(p.to_string_lossy().into_owned()));
            } else if inline {
                let mut table = toml::Table::new();
                for (k, v) in [
                    ("colour", t.colour),
                    ("opacity", t.opacity),
                    ("medium", t.medium),
                    ("eta", t.eta),
                ] {
                    if let Some(v) = v {
                        table.insert(k.into(), v);
                    }
                }
                let tf = TransferFunctions::parse(&table.to_string(), "[transfer]")?;
                o.transfer = Some(TransferSource::Inline(Box::new(tf)));
            }
        }
        if let Some(c) = self.camera {
            let mut target = s.camera.target;
            if let Some(t) = c.target {
                target = Vec3::from(t);
                ensure!(
                    target.is_finite(),
                    "[camera] target {t:?} must be finite numbers"
                );
                o.target = Some(target);
            }
            if let Some(eye) = c.eye {
                ensure!(
                    c.azimuth.is_none() && c.elevation.is_none() && c.distance.is_none(),
                    "[camera]: give eye (and target) or azimuth/elevation/distance, not both"
                );
                let eye = Vec3::from(eye);
                ensure!(eye.is_finite(), "[camera] eye {eye} must be finite numbers");
                // The camera orbits the target (the origin unless given) and looks at it.
                let e = eye - target;
                let d = e.length();
                ensure!(d > 0.0, "[camera] eye must differ from target");
                ensure!(
                    d <= crate::camera::MAX_DISTANCE,
                    "[camera] eye {eye} is {d:e} from the target, more than the {} a camera \
                     may be (the volume's box is 1 across)",
                    crate::camera::MAX_DISTANCE
                );
                o.distance = Some(d);
                o.elevation = Some(
                    (e.y / d)
                        .clamp(-1.0, 1.0)
                        .asin()
                        .to_degrees()
                        .clamp(-90.0, 90.0),
                );
                o.azimuth = Some(e.x.atan2(e.z).to_degrees());
            }
            o.azimuth = c.azimuth.or(o.azimuth);
            o.elevation = c.elevation.or(o.elevation);
            o.distance = c.distance.or(o.distance);
            o.fov = c.fov;
        }
        let mut more_lights = None;
        if let Some(v) = self.light {
            let tables = light_tables(v)?;
            let mut tables = tables.into_iter();
            if let Some((name, l)) = tables.next() {
                match (l.towards, l.position) {
                    (Some(_), Some(_)) => bail!(
                        "{name}: give towards (a directional light) or position (a point \
                         light), not both"
                    ),
                    (Some(Towards::Direction(d)), None) => {
                        o.light_source = Some(LightSource::directional(Vec3::from(d)))
                    }
                    (Some(Towards::Word(w)), None) if w.eq_ignore_ascii_case("env") => {
                        ensure!(
                            l.colour.is_none(),
                            "{name} towards = \"env\" takes the colour from the environment \
                             map too: drop its colour"
                        );
                        o.light_from_env = Some(true);
                    }
                    (Some(Towards::Word(w)), None) => bail!(
                        "{name} towards = \"{w}\": expected [x, y, z] or \"env\" (the \
                         environment map's brightest region)"
                    ),
                    (None, Some(p)) => {
                        o.light_source = Some(LightSource::Point {
                            position: Vec3::from(p),
                        })
                    }
                    (None, None) => {}
                }
                o.light_colour = l.colour;
                o.ambient_level = l.ambient_level;
                o.softness = l.softness;
            }
            let more: Vec<Light> = tables
                .map(|(name, l)| {
                    ensure!(
                        l.ambient_level.is_none(),
                        "{name}: ambient_level belongs to the first [[light]] table (the \
                         frame's ambient level, not a light's)"
                    );
                    let source = match (l.towards, l.position) {
                        (Some(Towards::Direction(d)), None) => {
                            LightSource::directional(Vec3::from(d))
                        }
                        (None, Some(p)) => LightSource::Point {
                            position: Vec3::from(p),
                        },
                        (Some(Towards::Word(w)), None) => bail!(
                            "{name} towards = \"{w}\": only the first light can come from \
                             the environment map; expected [x, y, z]"
                        ),
                        _ => bail!(
                            "{name}: give towards = [x, y, z] (a directional light) or \
                             position = [x, y, z] (a point light)"
                        ),
                    };
                    let light = Light {
                        source,
                        colour: l.colour.unwrap_or(Light::DEFAULT_COLOUR),
                        softness: l.softness.unwrap_or(Light::DEFAULT_SOFTNESS),
                    };
                    light.validate().with_context(|| name.clone())?;
                    Ok(light)
                })
                .collect::<Result<_>>()?;
            if !more.is_empty() {
                more_lights = Some(more);
            }
        }
        if let Some(e) = self.environment {
            if let Some(m) = e.map {
                o.environment = Some(match m.as_str() {
                    "sky" => EnvSource::Sky,
                    "none" => EnvSource::None,
                    f => EnvSource::File(rel(f)?),
                });
            }
            o.env_rotation = e.rotation;
        }
        // The models' options' values, checked once the model is known to take them.
        let mut model_values = Vec::new();
        if let Some(RenderSection { table: r, models }) = self.render {
            for (key, value) in models {
                let v = match value {
                    toml::Value::Integer(i) => i as f64,
                    toml::Value::Float(f) => f,
                    other => bail!(
                        "[render] {key}: expected a number, got {} {other}",
                        other.type_str()
                    ),
                };
                model_values.push((key, v));
            }
            if let Some(m) = r.model {
                o.model = Some(parse_model(&m).context("[render]")?);
            }
            crate::copy_plain_render_overrides!(o, r);
            o.preintegrated = r.preintegrated;
            o.background = r.background;
            // As --background: applies (no environment) or is an error.
            if r.background.is_some() {
                match &o.environment {
                    None | Some(EnvSource::None) => o.environment = Some(EnvSource::None),
                    Some(_) => bail!(
                        "[render] background and [environment] map: the environment is \
                         what lies behind the volume; give one of them"
                    ),
                }
            }
            if let Some(t) = &r.light_transport {
                o.light_transport =
                    Some(LightTransport::parse(t).context("[render] light_transport")?);
            }
            match &r.reflections {
                None => {}
                Some(Reflections::On(on)) => o.reflections = Some(*on),
                Some(Reflections::Mode(m)) => {
                    let volume = match m.to_ascii_lowercase().as_str() {
                        "volume" => true,
                        "environment" => false,
                        other => bail!(
                            "[render] reflections = \"{other}\": give true, false, \"volume\" \
                             or \"environment\""
                        ),
                    };
                    o.reflections = Some(true);
                    o.reflections_volume = Some(volume);
                }
            }
            o.clip = r.clip.map(|c| Some((Vec3::new(c[0], c[1], c[2]), c[3])));
            o.exposure = r.exposure;
            if let Some(lights) = &r.lights {
                ensure!(
                    more_lights.is_none(),
                    "[render] lights and more than one [[light]] table: give every light as \
                     a [[light]] table"
                );
                log::warn!(
                    "{}: [render] lights is deprecated; give each light as a [[light]] \
                     table (towards = [x, y, z] or position = [x, y, z], colour = [r, g, b])",
                    path.display()
                );
                more_lights = Some(
                    lights
                        .iter()
                        .map(|l| l.parse())
                        .collect::<Result<_>>()
                        .context("[render] lights")?,
                );
            }
            if let Some(t) = r.tonemap {
                o.tonemap = Some(parse_tonemap(&t).context("[render]")?);
            }
        }
        o.extra_lights = more_lights;
        s.apply(o);
        // A setting of other models is refused, as its flag is (the file's own model).
        super::refuse_what_does_not_apply(s.model, s.light_transport, &given)?;
        for (key, v) in model_values {
            let option = find_option(&key).expect("kept by name");
            s.models.set_as(option, v, &format!("[render] {key}"))?;
        }
        // Everything checkable without the GPU, now, with the scene's name on it.
        s.render_options()?;
        s.tone_map()?;
        Ok(s)
    }
}
