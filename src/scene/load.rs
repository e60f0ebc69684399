//! Loading what a scene names: its volume (generated, cached or read, with the notes a
//! user should see), the transfer functions, environment and label map, checked
//! together, and the files a scene reads (for the viewer's reload poll).

use super::*;

impl Scene {
    /// The volume, generated, loaded from the cache, or read from its file. `data_dir`
    /// holds the fetched scans and, for stand-ins, the thesis originals if the user has
    /// them (`<name>.<ext>` in any supported format). With `limits`, a file the device
    /// cannot hold is refused from its header, before its data is read.
    pub fn load_volume(&self, data_dir: &Path, limits: Option<DeviceLimits>) -> Result<Volume> {
        self.load_volume_noted(data_dir, limits).map(|(v, _)| v)
    }

    /// [`Scene::load_volume`], and what it did that the user should know (turned upright).
    fn load_volume_noted(
        &self,
        data_dir: &Path,
        limits: Option<DeviceLimits>,
    ) -> Result<(Volume, Vec<String>)> {
        let mut notes = Vec::new();
        let mut vol = match &self.volume {
            VolumeSource::Procedural { kind, size } => procedural_volume(kind, *size)?,
            VolumeSource::Standin { name, scale } => {
                if let Some(orig) = original_in(data_dir, name) {
                    log::info!("{name}: using the original {}", orig.display());
                    load_file(&orig, None, None, limits)?
                } else {
                    let d = standins::dataset(name)?;
                    let dims = standins::scaled_dims(d.dims, *scale)?;
                    // Before generating (and caching) it: --scale 2 on the glass stand-in
                    // wrote 3.8 GB to the cache and was refused only then.
                    if let Some(l) = limits {
                        crate::volume::formats::check_limits_texel(
                            dims,
                            1,
                            l.max_3d_extent,
                            l.bytes_available,
                        )
                        .with_context(|| format!("the {name} stand-in at scale {scale}"))?;
                    }
                    standins::load_or_generate(name, dims, &standins::cache_dir())?.0
                }
            }
            VolumeSource::File { path, raw, window } => load_file(path, *raw, *window, limits)?,
            VolumeSource::Fetched { file, window } => {
                let path = data_dir.join(file);
                ensure!(
                    path.exists(),
                    "{}: not found; run scripts/fetch-data (or set REFRAKT_DATA_DIR / --data-dir to where it put the data)",
                    path.display()
                );
                load_file(&path, None, *window, limits)?
            }
        };
        if let Some(s) = self.spacing {
            vol.spacing = s;
            vol.validate().with_context(|| match &self.file {
                Some(f) => format!(
                    "the spacing {s:?} given by scene {} or --spacing",
                    f.display()
                ),
                None => format!("--spacing {s:?}"),
            })?;
        }
        let file = match &self.volume {
            VolumeSource::File { path, .. } => Some(path.clone()),
            VolumeSource::Fetched { file, .. } => Some(data_dir.join(file)),
            _ => None,
        };
        if let Some(axes) = self.orientation {
            ensure!(
                file.is_some(),
                "an orientation (--orientation, [volume] orientation) applies to volume \
                 files; '{}' is a built-in scene",
                self.name
            );
            ensure!(
                self.upright,
                "an orientation (--orientation, [volume] orientation) is used to turn the \
                 volume upright, which --upright off (or [volume] upright = false) turns \
                 off: drop one of them"
            );
            vol.axes = Some(axes);
        }
        if let (Some(f), false, None) = (&file, vol.spacing_stated, self.spacing) {
            log::warn!(
                "{}: the file does not state its voxel spacing, so 1 × 1 × 1 (cubic voxels) \
                 is assumed; if the volume looks squashed or stretched, give --spacing X,Y,Z{}",
                f.display(),
                if crate::volume::formats::is_raw(f) {
                    " or a sidecar NAME.json with \"spacing\": [x, y, z] beside the raw file"
                } else {
                    ""
                }
            );
        }
        if self.upright {
            notes.extend(vol.turn_upright());
        }
        if let Some(r) = self.rotate {
            vol.rotate(r);
        }
        vol.flip(self.flip);
        Ok((vol, notes))
    }

    /// Loads everything: volume, transfer functions, environment map; checks the options.
    /// `limits`: see [`Scene::load_volume`].
    pub fn load_all(&self, data_dir: &Path, limits: Option<DeviceLimits>) -> Result<LoadedScene> {
        // An error from what a scene file says names the file (the volume's size, scale,
        // the camera...), as the parser's errors do.
        match &self.file {
            Some(f) => self
                .load_all_unnamed(data_dir, limits)
                .with_context(|| format!("scene {}", f.display())),
            None => self.load_all_unnamed(data_dir, limits),
        }
    }

    fn load_all_unnamed(
        &self,
        data_dir: &Path,
        limits: Option<DeviceLimits>,
    ) -> Result<LoadedScene> {
        let mut opts = self.render_options()?;
        let tone = self.tone_map()?;
        let env = self.environment_map()?;
        let mut light_note = None;
        if self.light_from_env {
            let Some(map) = &env else {
                bail!(
                    "the light is to come from the environment (--light env, [light] towards \
                     = \"env\"), but there is no environment map: give --env FILE or --env sky"
                );
            };
            let key = map.key_light().ok_or_else(|| {
                anyhow::anyhow!(
                    "the light from the environment (--light env, [light] towards = \"env\"): \
                     the environment map is black everywhere; it gives no light"
                )
            })?;
            let towards = Vec3::from(key.world_towards(self.env_rotation));
            // The sweep takes light from the viewer's side only: a map whose brightest
            // region is behind the volume is said here, with the turn of the map that
            // brings it round to the camera's side.
            let (_, forward, _, _) = self.camera.frame();
            if self.model == Model::Refract
                && (-towards).dot(forward) < crate::render::limits::MIN_FORWARD
            {
                let angle = |v: Vec3| v.z.atan2(v.x).to_degrees();
                let turn = angle(towards) - angle(-forward);
                let r = (self.env_rotation + turn + 540.0).rem_euclid(360.0) - 180.0;
                bail!(
                    "the light from the environment (--light env, [light] towards = \"env\"): \
                     the map's brightest region (towards ({:.2}, \
                     {:.2}, {:.2})) lies behind the volume as this camera sees it, and the \
                     sweep takes light from the viewer's side only; turn the map with \
                     --env-rotation {r:.0} (the camera's side), move the camera, or give \
                     --light X,Y,Z",
                    towards.x,
                    towards.y,
                    towards.z
                );
            }
            opts.light_mut().set_towards(towards);
            opts.light_mut().colour = key.colour;
            // An ambient level given explicitly wins over the map's.
            if self.ambient_level.is_none() {
                opts.sweep.ambient = key.ambient;
            }
            let ambient = opts.sweep.ambient;
            let whose = match (self.ambient_level.is_some(), self.model == Model::Refract) {
                (true, _) => "as given",
                (false, true) => "the rest of the map's mean radiance",
                (false, false) => "the rest of the map's mean radiance; the refract model's only",
            };
            light_note = Some(format!(
                "light from the environment's brightest region: towards ({:.3}, {:.3}, {:.3}) \
                 ({:.0}° above the horizon), {:.4} sr, irradiance ({:.3}, {:.3}, {:.3}); \
                 ambient ({:.4}, {:.4}, {:.4}: {whose})",
                towards.x,
                towards.y,
                towards.z,
                towards.y.clamp(-1.0, 1.0).asin().to_degrees(),
                key.solid_angle,
                key.colour[0],
                key.colour[1],
                key.colour[2],
                ambient[0],
                ambient[1],
                ambient[2]
            ));
            opts.validate()?;
        }
        let derived = matches!(self.transfer, TransferSource::FromData);
        let tf = if derived {
            None
        } else {
            Some(self.transfer_functions()?)
        };
        let (mut volume, upright) = self.load_volume_noted(data_dir, limits)?;
        let mut tf = tf;
        let mut label_note = None;
        if let Some((labels_tf, note)) = self.label_map(&mut volume, derived)? {
            tf = Some(labels_tf);
            label_note = Some(note);
        }
        if self.model == Model::Refract {
            // The sweep's planes need the camera outside the box: said now, with the scene
            // file named (load_all), not after the device has been set up.
            let half = Vec3::from(volume.normalised_extent()) * 0.5;
            crate::render::Planes::for_box(
                &self.camera,
                half,
                opts.sample_distance * volume.min_voxel_size(),
            )?;
        }
        let (tf, mut notes) = self.check_data(&volume, tf);
        notes.extend(label_note);
        notes.extend(upright);
        notes.extend(light_note);
        let files = self.input_files(data_dir);
        let env_name = match &self.environment {
            EnvSource::Sky => "sky".to_string(),
            EnvSource::None => "none".to_string(),
            EnvSource::File(p) => p
                .file_name()
                .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into()),
        };
        Ok(LoadedScene {
            name: self.name.clone(),
            volume,
            tf,
            env,
            env_name,
            model: self.model,
            camera: self.camera,
            opts,
            tone,
            files,
            notes,
        })
    }

    /// The categorical transfer functions of a label volume, and a note, when the scene
    /// asks for labels or detects them (`derived`: the transfer functions are the data's
    /// own); marks the volume for nearest-voxel classification.
    fn label_map(
        &self,
        volume: &mut Volume,
        derived: bool,
    ) -> Result<Option<(TransferFunctions, String)>> {
        use crate::labels;
        let from_file = matches!(
            self.volume,
            VolumeSource::File { .. } | VolumeSource::Fetched { .. }
        );
        let forced = matches!(self.labels, LabelChoice::On | LabelChoice::Table(_));
        if forced || self.labels == LabelChoice::Off {
            ensure!(
                from_file,
                "--labels applies to volume files; '{}' is a built-in scene",
                self.name
            );
        }
        if forced {
            ensure!(
                derived,
                "--labels makes the transfer functions from the labels: drop --tf (or \
                 [transfer])"
            );
        }
        if !from_file || !derived || self.labels == LabelChoice::Off {
            return Ok(None);
        }
        let max = if forced {
            labels::MAX_LABELS
        } else {
            labels::MAX_AUTO_LABELS
        };
        let integer_file = volume.stored.is_some_and(|t| t.contains("int"));
        let values = match labels::distinct_values(volume, max) {
            Some(v) if forced || (integer_file && v.len() >= 2) => v,
            Some(_) | None if !forced => return Ok(None),
            _ => bail!(
                "--labels: the volume's values are not a label map (more than {max} \
                 distinct values, the most labels refrakt tells apart, or values that are \
                 not integers)"
            ),
        };
        let (table, source) = match &self.labels {
            LabelChoice::Table(path) => (labels::read_table(path)?, format!("{}", path.display())),
            _ => (
                labels::default_labels(&values),
                "the built-in palette".into(),
            ),
        };
        // The voxels become label indices (label k at k / 255 on the GPU), the table and
        // the transfer functions with them.
        let indices: Vec<f64> = (0..values.len()).map(|k| k as f64).collect();
        let tf = labels::categorical(
            &labels::indexed_table(&table, &values),
            &indices,
            (0.0, 255.0),
        );
        labels::index_voxels(volume, &values)?;
        volume.labels = true;
        let missing = values
            .iter()
            .filter(|v| !table.iter().any(|l| l.value == **v))
            .count();
        let mut note = format!(
            "label volume: {} labels ({} .. {}), colours from {source}; classified by the \
             nearest voxel (a segment between two labels is half each){}",
            values.len(),
            values[0],
            values[values.len() - 1],
            if self.labels == LabelChoice::Auto {
                " (detected; --labels off treats the values as a scan)"
            } else {
                ""
            }
        );
        if missing > 0 {
            note.push_str(&format!(
                "; {missing} of the volume's values are not in the table and are not drawn"
            ));
        }
        Ok(Some((tf, note)))
    }

    /// The files this scene reads (scene file, transfer functions, environment map, volume
    /// file or the original of a stand-in), those that exist: what the viewer watches,
    /// and what no command may write over (issue 33).
    pub fn input_files(&self, data_dir: &Path) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = self.file.iter().cloned().collect();
        if let TransferSource::Named(n) = &self.transfer {
            if Path::new(n).is_file() {
                files.push(PathBuf::from(n));
            }
        }
        if let EnvSource::File(p) = &self.environment {
            files.push(p.clone());
        }
        match &self.volume {
            VolumeSource::File { path, .. } if path.is_file() => {
                files.push(path.clone());
                // A raw file's JSON sidecar, which may state its spacing.
                if crate::volume::formats::is_raw(path) {
                    let sidecars = crate::volume::formats::raw_sidecars(path);
                    files.extend(sidecars.into_iter().filter(|p| p.is_file()));
                }
            }
            VolumeSource::Fetched { file, .. } => files.push(data_dir.join(file)),
            VolumeSource::Standin { name, .. } => files.extend(original_in(data_dir, name)),
            _ => {}
        }
        files
    }
}

/// A volume file with an optional raw layout and value window.
fn load_file(
    path: &Path,
    raw: Option<crate::volume::formats::RawLayout>,
    window: Option<(f32, f32)>,
    limits: Option<DeviceLimits>,
) -> Result<Volume> {
    let opts = crate::volume::formats::LoadOptions {
        raw,
        window,
        spacing: None,
        limits,
    };
    crate::volume::formats::load_volume(path, &opts)
}
