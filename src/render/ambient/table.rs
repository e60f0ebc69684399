//! TEMPORARY STUB (replaced by the Monte-Carlo table): the API the GPU side codes against.
#![allow(dead_code)]
use std::path::Path;

use anyhow::Result;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableParams {
    pub albedo: f32,
    pub theta_bins: u32,
    pub s_bins: u32,
    pub g_bins: u32,
    pub s_max: f32,
    pub paths: u32,
    pub seed: u64,
}

impl Default for TableParams {
    fn default() -> Self {
        Self {
            albedo: 0.9,
            theta_bins: 33,
            s_bins: 48,
            g_bins: 23,
            s_max: 64.0,
            paths: 64,
            seed: 1,
        }
    }
}

impl TableParams {
    pub fn validate(&self) -> Result<()> {
        Ok(())
    }
    pub fn s(&self, k: u32) -> f64 {
        let u = k as f64 / (self.s_bins - 1) as f64;
        (1.0 + self.s_max as f64).powf(u) - 1.0
    }
}

pub const G_MAX: f32 = 0.99;

#[derive(Clone, Debug)]
pub struct AmbientTable {
    pub params: TableParams,
    pub scattered: Vec<f32>,
    pub transmission: Vec<f32>,
    pub seconds: f64,
}

pub enum Source {
    Cached(std::path::PathBuf),
    Built {
        seconds: f64,
        written: Option<std::path::PathBuf>,
    },
}

impl AmbientTable {
    pub fn load(_p: &Path) -> Result<Self> {
        anyhow::bail!("stub")
    }
    pub fn s_at(&self, k: u32) -> f32 {
        self.params.s(k) as f32
    }
    pub fn s_old(&self, k: u32) -> f32 {
        let u = k as f32 / (self.params.s_bins - 1) as f32;
        (1.0 + self.params.s_max).powf(u) - 1.0
    }
    pub fn build(
        params: &TableParams,
        _threads: usize,
        _p: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<Self> {
        let p = *params;
        let mut scattered = vec![0.0; (p.theta_bins * p.s_bins * p.g_bins) as usize];
        let mut transmission = vec![0.0; (p.s_bins * p.g_bins) as usize];
        let t = Self {
            params: p,
            scattered: vec![],
            transmission: vec![],
            seconds: 0.0,
        };
        for m in 0..p.g_bins {
            for k in 0..p.s_bins {
                let s = t.s_at(k);
                transmission[(m * p.s_bins + k) as usize] = (-2.0 * s).exp();
                for i in 0..p.theta_bins {
                    scattered[((m * p.s_bins + k) * p.theta_bins + i) as usize] = 0.0;
                }
            }
        }
        Ok(Self {
            params: p,
            scattered,
            transmission,
            seconds: 0.0,
        })
    }
}

pub fn load_or_build(
    params: &TableParams,
    _cache_dir: Option<&Path>,
    threads: usize,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<(AmbientTable, Source)> {
    Ok((
        AmbientTable::build(params, threads, progress)?,
        Source::Built {
            seconds: 0.0,
            written: None,
        },
    ))
}
