//! Packed geometry in the layouts other than the default, kept between passes.

use std::any::Any;

use super::pack::Geometry;
use crate::geometry::layout::{Aos, Hybrid, Layout, Soa, SoaSimd};

/// Geometry in the layouts other than the default, made on demand from the default-layout
/// geometry and kept until that geometry is rebuilt. The render system holds one, so a
/// `--layout` other than the default costs one [`Geometry::relayout`] per BVH build (a copy of
/// the arrays and BVHs, linear in the primitives), not one per pass.
#[derive(Default)]
pub struct LayoutCache {
    source: u64,
    soa: Option<Geometry<Soa>>,
    aos: Option<Geometry<Aos>>,
    soa_simd: Option<Geometry<SoaSimd>>,
    hybrid: Option<Geometry<Hybrid>>,
}

/// Layouts that have a slot in [`LayoutCache`].
pub trait Cached: Layout {
    /// This layout's slot.
    fn slot(cache: &mut LayoutCache) -> &mut Option<Geometry<Self>>;
}

impl Cached for Soa {
    fn slot(cache: &mut LayoutCache) -> &mut Option<Geometry<Self>> {
        &mut cache.soa
    }
}

impl Cached for Aos {
    fn slot(cache: &mut LayoutCache) -> &mut Option<Geometry<Self>> {
        &mut cache.aos
    }
}

impl Cached for SoaSimd {
    fn slot(cache: &mut LayoutCache) -> &mut Option<Geometry<Self>> {
        &mut cache.soa_simd
    }
}

impl Cached for Hybrid {
    fn slot(cache: &mut LayoutCache) -> &mut Option<Geometry<Self>> {
        &mut cache.hybrid
    }
}

impl LayoutCache {
    /// `geometry` in layout `L`: itself if `L` is its layout, else a copy made now or kept from
    /// an earlier call with the same `version` (any number that changes whenever `geometry` is
    /// rebuilt; a new version drops every copy).
    pub fn get<'a, L: Cached>(
        &'a mut self,
        geometry: &'a Geometry,
        version: u64,
    ) -> &'a Geometry<L> {
        // A type check once per pass, never per ray.
        if let Some(same) = (geometry as &dyn Any).downcast_ref::<Geometry<L>>() {
            return same;
        }
        if self.source != version {
            *self = Self {
                source: version,
                ..Self::default()
            };
        }
        L::slot(self).get_or_insert_with(|| geometry.relayout())
    }
}
