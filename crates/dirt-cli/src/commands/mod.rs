//! One module per `dirt` subcommand: its arguments and what it does.

pub mod bench;
pub mod eval;
pub mod explain;
pub mod info;
pub mod rays;
pub mod render;
pub mod trace;
pub mod triangles;
pub mod view;

/// Milliseconds of a duration, for the timing lines commands print.
pub fn millis(d: std::time::Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
