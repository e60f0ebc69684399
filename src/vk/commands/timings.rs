//! GPU timestamp scopes: the query pool of a recording and the named times it resolves to.

use anyhow::Result;
use ash::vk;

use crate::vk::Context;

use super::*;

/// Enough for per-plane scopes of a profile (three per plane, 2 timestamps each, over a
/// thousand planes).
pub(super) const MAX_QUERIES: u32 = 8192;

/// GPU time of each named scope, in recording order, in milliseconds.
#[derive(Clone, Debug, Default)]
pub struct Timings {
    pub scopes: Vec<(String, f64)>,
}

impl Timings {
    /// Sum of all scopes with this name.
    pub fn get(&self, name: &str) -> Option<f64> {
        let v: Vec<f64> = self
            .scopes
            .iter()
            .filter(|(n, _)| n == name)
            .map(|(_, t)| *t)
            .collect();
        (!v.is_empty()).then(|| v.iter().sum())
    }
    pub fn extend(&mut self, other: Timings) {
        self.scopes.extend(other.scopes);
    }
}

/// The timestamp scopes of a finished recording, resolved into [`Timings`] once the
/// submission has completed ([`PendingTimings::resolve`]).
pub struct PendingTimings {
    pub(super) scopes: Vec<Scope>,
    pub(super) used: u32,
    /// The fraction each progress mark stands for (empty unless observed).
    pub(super) marks: Vec<f64>,
}

impl PendingTimings {
    /// Read the timestamps from `queries` (the pool the recording used). Call only after
    /// the submission has completed.
    pub(crate) fn resolve(self, ctx: &Context, queries: Option<vk::QueryPool>) -> Result<Timings> {
        let mut timings = Timings::default();
        let (Some(q), true) = (queries, self.used > 0) else {
            return Ok(timings);
        };
        let mut raw = vec![0u64; self.used as usize];
        // SAFETY: `used` queries were written and the work has completed.
        unsafe {
            ctx.device().get_query_pool_results(
                q,
                0,
                &mut raw,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }?;
        let period = ctx.info().limits.timestamp_period as f64;
        for s in self.scopes {
            if let (Some(e), true) = (s.end, s.begin != u32::MAX) {
                let ticks = raw[e as usize].saturating_sub(raw[s.begin as usize]);
                timings.scopes.push((s.name, ticks as f64 * period * 1e-6));
            }
        }
        Ok(timings)
    }
}

/// A timestamp query pool large enough for one recording's scopes (None when the device
/// has no timestamps).
pub(crate) fn create_query_pool(ctx: &Context) -> Result<Option<vk::QueryPool>> {
    if !ctx.info().timestamps {
        return Ok(None);
    }
    let info = vk::QueryPoolCreateInfo::default()
        .query_type(vk::QueryType::TIMESTAMP)
        .query_count(MAX_QUERIES);
    // SAFETY: valid device.
    Ok(Some(unsafe {
        ctx.device().create_query_pool(&info, None)
    }?))
}
