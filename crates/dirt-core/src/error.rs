//! The errors of the backend-neutral layer and of any [`crate::Tracer`].

use std::error::Error;

/// Errors of parameters, input triangles and tracers.
#[derive(Debug, thiserror::Error)]
pub enum CoreError {
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
    #[error("triangle {index} has a non-finite vertex coordinate")]
    NonFiniteTriangle { index: usize },
    #[error("{tracer}: trace called before build")]
    NotBuilt { tracer: String },
    #[error("{what} holds {got} entries for {expected} rays")]
    BufferLength {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    /// A backend's own error (GPU, Embree, …), kept whole as the source.
    #[error("{tracer}: {source}")]
    Backend {
        tracer: String,
        source: Box<dyn Error + Send + Sync>,
    },
}

impl CoreError {
    /// Wraps a backend's error, naming the tracer.
    pub fn backend(tracer: impl Into<String>, source: impl Error + Send + Sync + 'static) -> Self {
        CoreError::Backend {
            tracer: tracer.into(),
            source: Box::new(source),
        }
    }
}
