//! Analysis: how much each technique reduces the error of an image. Knows nothing of how images
//! are made beyond Films, EXR files and the renderer's public entry points.
//!
//! - [`calibration`]: an image's own error estimate against the error measured;
//! - [`metrics`]: MSE, relMSE, RMSE, MAE, variance across runs, bias tests, error maps;
//! - [`experiments`]: `compare` (strategies at equal spp or equal time, over K runs) and
//!   `converge` (error against spp, each spp rendered from scratch, with fitted slopes);
//! - [`merge`]: renders made in pieces combined exactly into one reference;
//! - [`fit`]: least-squares lines and log-log slopes;
//! - [`plots`]: log-log convergence and calibration plots (SVG/PNG);
//! - [`maps`]: false-colour maps (error, samples per pixel, EARS factor, densities) and the
//!   labelled image grid of a comparison (PNG);
//! - [`points`]: a sampler's points in the unit square, their discrepancy and spectrum;
//! - [`theory_plots`]: the pictures of `vrpt points` and `vrpt integrate`;
//! - [`integrate`]: known-answer integrals by each sampler, against the variance formulas;
//! - [`report`]: the self-contained HTML report of compare, converge and diff.

#![warn(missing_docs)]

pub mod calibration;
pub mod experiments;
pub mod fit;
pub mod integrate;
pub mod maps;
pub mod merge;
pub mod metrics;
pub mod plots;
pub mod points;
pub mod report;
pub mod theory_plots;
