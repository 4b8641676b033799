//! The knobs of the structure ([`AdsParams`]) and of its walk ([`Traversal`]).

use crate::CoreError;
use dirt_math::view::Axis;
use dirt_math::{Aabb, Vec3, ViewsKind};
use std::fmt;

/// How a ray walks the tiles it crosses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Traversal {
    /// Conservative 2D DDA over the finest tiles.
    #[default]
    Linear,
    /// Hierarchical stepping over the Hi-Z pyramid.
    #[cfg_attr(feature = "clap", value(name = "hiz"))]
    HiZ,
}

impl Traversal {
    /// Both traversals, in a fixed order.
    pub const ALL: [Traversal; 2] = [Traversal::Linear, Traversal::HiZ];

    /// The name used on command lines and in reports: `linear` or `hiz`.
    pub fn name(self) -> &'static str {
        match self {
            Traversal::Linear => "linear",
            Traversal::HiZ => "hiz",
        }
    }
}

impl fmt::Display for Traversal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Build parameters of the acceleration structure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdsParams {
    pub views: ViewsKind,
    /// Face resolution in pixels (square faces).
    pub resolution: u32,
    /// Depth buckets per tile (B).
    pub buckets: u32,
    /// Tile size in pixels (S); must divide `resolution`.
    pub tile: u32,
    /// Cube: the centre of the views. Single: the eye. `None`: the centre of
    /// the scene bounds for the cube; outside the bounds, seeing all of them, for the single view.
    /// Split orthographic views: a point of the cutting plane (`None`: the
    /// bounds' centre, the spatial median). One orthographic view takes none.
    pub center: Option<Vec3>,
    /// Orthographic views: the axis they look along (`None`: the bounds'
    /// thinnest, [`Axis::thinnest`]). Perspective views take none.
    pub axis: Option<Axis>,
}

impl Default for AdsParams {
    fn default() -> Self {
        Self {
            views: ViewsKind::Cube,
            resolution: 128,
            buckets: 8,
            tile: 1,
            center: None,
            axis: None,
        }
    }
}

impl AdsParams {
    /// Tiles per side of each view.
    pub fn tiles(&self) -> u32 {
        self.resolution / self.tile.max(1)
    }

    /// The axis orthographic views look along over `bounds`: `axis`, else
    /// the bounds' thinnest.
    pub fn ortho_axis(&self, bounds: &Aabb) -> Axis {
        self.axis.unwrap_or_else(|| Axis::thinnest(bounds.extent()))
    }

    /// Checks the parameters before any work is done.
    pub fn validate(&self) -> Result<(), CoreError> {
        let bad = |m: String| Err(CoreError::InvalidParams(m));
        if self.resolution == 0 || self.resolution > 16384 {
            return bad(format!(
                "resolution must be in 1..=16384, got {}",
                self.resolution
            ));
        }
        if self.tile == 0 || !self.resolution.is_multiple_of(self.tile) {
            return bad(format!(
                "tile size {} must be >= 1 and divide the resolution {}",
                self.tile, self.resolution
            ));
        }
        if self.buckets == 0 || self.buckets > 4096 {
            return bad(format!("buckets must be in 1..=4096, got {}", self.buckets));
        }
        if let Some(c) = self.center
            && !c.is_finite()
        {
            return bad(format!("center must be finite, got {c}"));
        }
        if self.views == ViewsKind::Ortho && self.center.is_some() {
            return bad("one orthographic view takes no centre".into());
        }
        if !self.views.is_ortho() && self.axis.is_some() {
            return bad(format!("{} views take no axis", self.views));
        }
        let lists = 6u64 * (self.tiles() as u64).pow(2) * self.buckets as u64;
        if lists >= u32::MAX as u64 {
            return bad(format!(
                "{lists} lists (views × tiles² × buckets) is more than the structure can index"
            ));
        }
        Ok(())
    }
}
