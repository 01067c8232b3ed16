//! vrpt's integration tests, one module per subject, in one test binary: each file under
//! `tests/` used to be a binary of its own that linked the whole crate (21 links at opt-level 3
//! took about half of `cargo test` from a fresh clone). The fuzz test stays a binary of its own:
//! its counting allocator must see no other test's allocations. Run one module with
//! `cargo test --test suite cli::`.

mod architecture;
mod auto;
mod cli;
#[path = "../common/mod.rs"]
mod common;
mod custom_sampler;
mod edges;
mod environment_map;
mod error_estimate;
mod experiments;
mod guiding;
mod hostile_inputs;
mod light_sampling;
mod real_scenes;
mod render_core;
mod report_browser;
mod reuse;
mod roulette;
mod scale_out;
mod scene_loading;
mod sobol;
mod textures;
mod unbiased_images;
mod variance_reduction;
mod warps_and_material;
