//! The renderer's resources that models share, made on a model's first need and
//! rebuilt when their inputs change: the gradient volume, the field texture, the
//! extinction volume (with its summed-area table) and each model's own state
//! (`ModelState`, declared in its `OpticalModel`).

use super::*;

impl Renderer {
    /// Build the gradient volume if `model` needs it and it is not there yet: its own
    /// submission, waited for (once per volume; a caller's open recording is unaffected,
    /// it is submitted later).
    pub(super) fn ensure_gradient(&mut self, model: Model) -> Result<()> {
        if !model.declaration().gradient
            || self.gradient_status != gradient::GradientStatus::Unbuilt
        {
            return Ok(());
        }
        let (ranges, t) =
            value_ranges::ValueRanges::build(&self.ctx, &self.volume_tex, &self.linear)?;
        self.value_ranges = Some(ranges);
        self.gradient_timings = t;
        let (needed, device_budget) =
            gradient::GradientVolume::memory(&self.ctx, self.volume_tex.extent());
        let budget = self.gradient_budget.unwrap_or(device_budget);
        if needed > budget {
            self.gradient_status = gradient::GradientStatus::TooLarge { needed, budget };
            return Ok(());
        }
        let (g, t) = gradient::GradientVolume::build(&self.ctx, &self.volume_tex, &self.linear)?;
        self.gradient = Some(g);
        self.gradient_status = gradient::GradientStatus::Built;
        self.gradient_timings.extend(t);
        Ok(())
    }

    /// Make the field texture the first time a frame of `model` asks for it (the sweep's
    /// `field` lever), once: beside the gradient volume (8 bytes per voxel once built) in
    /// the same budget; built in the frame's recording.
    pub(super) fn ensure_field(&mut self, model: Model, opts: &RenderOptions) -> Result<()> {
        if !model.declaration().gradient || !opts.sweep.levers.field || self.field_checked {
            return Ok(());
        }
        self.field_checked = true;
        let extent = self.volume_tex.extent();
        let (gradient_build, device_budget) = gradient::GradientVolume::memory(&self.ctx, extent);
        let budget = self.gradient_budget.unwrap_or(device_budget);
        let gradient = if self.gradient.is_some() {
            gradient_build / 2
        } else {
            0
        };
        if gradient + field::FieldTexture::bytes(extent) <= budget {
            self.field = Some(field::FieldTexture::new(
                &self.ctx,
                &self.volume_tex,
                &self.tf_image,
                &self.linear,
            )?);
            self.field_dirty = true;
            // The pass's descriptor set names the volume in the field's place: make it anew.
            self.remove_passes(model);
        }
        Ok(())
    }

    /// Make the extinction volume and its 3D SAT the first time a frame of `model` needs
    /// them (the ambient models); built in the frame's recording. Refused with the sizes
    /// when they do not fit the device's budget (the gradient volume's).
    pub(super) fn ensure_extinction(&mut self, model: Model) -> Result<()> {
        let declared = model.declaration();
        let Some(with_sat) = declared.extinction else {
            return Ok(());
        };
        let has_sat = self.extinction.as_ref().is_some_and(|e| e.sat().is_ok());
        // The model's own state is made from the extinction volume (the transmittance
        // cache) and shares its budget.
        let new_state = declared
            .state
            .as_ref()
            .filter(|_| !self.states.contains_key(&model));
        if self.extinction.is_some() && (has_sat || !with_sat) && new_state.is_none() {
            return Ok(());
        }
        let extent = self.volume_tex.extent();
        let (_, device_budget) = gradient::GradientVolume::memory(&self.ctx, extent);
        let budget = self.gradient_budget.unwrap_or(device_budget);
        let state_bytes = new_state.map_or(0, |s| (s.bytes)(extent));
        let needed = extinction::Extinction::bytes(extent, with_sat || has_sat)
            + self.states.values().map(|s| s.bytes()).sum::<u64>()
            + state_bytes;
        ensure!(
            needed <= budget,
            "the {} model needs {} MiB for the extinction volume{} ({}x{}x{} voxels); the \
             device budget is {} MiB: use a smaller volume (--scale)",
            model.name(),
            needed >> 20,
            match new_state {
                _ if with_sat => " and its summed-area table".to_string(),
                Some(s) if state_bytes > 0 => format!(" and {}", s.what),
                _ => String::new(),
            },
            extent[0],
            extent[1],
            extent[2],
            budget >> 20
        );
        if self.extinction.is_none() {
            self.extinction = Some(extinction::Extinction::new(
                &self.ctx,
                &self.volume_tex,
                &self.tf_image,
                &self.linear,
            )?);
            self.extinction_dirty = true;
        }
        let extinction = self.extinction.as_mut().expect("made above");
        if with_sat && !has_sat {
            extinction.add_sat(&self.ctx)?;
            self.extinction_dirty = true;
        }
        Ok(())
    }

    /// `model`'s own state ([`model::OpticalModel::state`]), made now if it has none yet
    /// (after the extinction volume it may be made from); an error for a model without
    /// state.
    pub(super) fn model_state(&mut self, model: Model) -> Result<&mut Box<dyn model::ModelState>> {
        let Some(decl) = &model.declaration().state else {
            bail!("the {} model keeps no state", model.name());
        };
        if !self.states.contains_key(&model) {
            let shared = model::Shared {
                ctx: &self.ctx,
                info: self.volume_info,
                extinction: self.extinction.as_ref(),
                linear: &self.linear,
                volume: &self.volume_tex,
                volume_sampler: &self.volume_sampler,
                tf: &self.tf_image,
                tf_changes: self.tf_changes,
                progress: self.build_progress.as_deref(),
            };
            let state = (decl.make)(&shared)?;
            self.states.insert(model, state);
        }
        Ok(self.states.get_mut(&model).expect("made above"))
    }

    /// `model`'s state if it has been made.
    pub(super) fn existing_model_state(&self, model: Model) -> Option<&dyn model::ModelState> {
        self.states.get(&model).map(|s| s.as_ref())
    }

    /// Make `model`'s state on its first frame and prepare it for a frame of `opts`
    /// (outside the recording); its passes are remade when what they bind changed.
    pub(super) fn ensure_state(&mut self, model: Model, opts: &RenderOptions) -> Result<()> {
        if model.declaration().state.is_none() {
            return Ok(());
        }
        self.model_state(model)?;
        let shared = model::Shared {
            ctx: &self.ctx,
            info: self.volume_info,
            extinction: self.extinction.as_ref(),
            linear: &self.linear,
            volume: &self.volume_tex,
            volume_sampler: &self.volume_sampler,
            tf: &self.tf_image,
            tf_changes: self.tf_changes,
            progress: self.build_progress.as_deref(),
        };
        let state = self.states.get_mut(&model).expect("made above");
        if state.prepare(&shared, opts)? {
            self.remove_passes(model);
        }
        Ok(())
    }
}
