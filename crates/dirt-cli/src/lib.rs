//! The library half of the `dirt` command line: its `.npy` interface, so that
//! the binary, the tests and the fuzz targets read rays with the same code.

pub mod npy;
