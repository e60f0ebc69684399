//! The command line, split by job: the syntax (`args`), the scene a command draws
//! (`scene_args`), and one module per subcommand.

pub mod ambient;
pub mod args;
pub mod bench;
pub mod bench_args;
pub mod info;
pub mod model_flags;
pub mod photons;
pub mod precompute;
pub mod reference;
pub mod render;
pub mod scene_args;
pub mod scene_flags;
pub mod view;
