// TEMPORARY STUB (not committed): replaced by the formats branch.
use anyhow::{bail, Result};
use std::path::Path;
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScalarKind {
    U8,
    U16,
    I16,
    F32,
}
#[derive(Clone, Debug, PartialEq)]
pub struct RawLayout {
    pub dims: [u32; 3],
    pub kind: ScalarKind,
    pub spacing: Option<[f32; 3]>,
}
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    pub raw: Option<RawLayout>,
    pub window: Option<(f32, f32)>,
    pub spacing: Option<[f32; 3]>,
}
pub fn load_volume(path: &Path, _o: &LoadOptions) -> Result<super::Volume> {
    bail!("stub {}", path.display())
}
pub fn is_volume_file(_p: &Path) -> bool {
    false
}
