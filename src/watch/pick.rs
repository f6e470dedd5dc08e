//! Picking for a viewer: after each frame that applied a scene or rebuilt its geometry, the id
//! buffer of the world as it now is and where its entities come from go to the pick sink (set
//! with [`Watch::set_pick_sink`]). Without a sink nothing is traced or kept. The ids are traced
//! again only when the scene version or the geometry changed: a reload that changes nothing
//! (a comment edited) sends the same ids with the new locations.

use std::sync::Arc;

use super::Watch;
use crate::scene::provenance::Provenance;
use crate::systems::IdBuffer;

/// What the pick sink gets: the ids of the image of reload `reload` and where their entities
/// come from (`ids.ids[p]` indexes `provenance`'s entries).
#[derive(Clone)]
pub struct Picked {
    /// The reload whose scene this is.
    pub reload: u64,
    /// The entity each pixel's central camera ray hits first.
    pub ids: Arc<IdBuffer>,
    /// Where each entity comes from.
    pub provenance: Arc<Provenance>,
}

/// Where the watch loop hands each [`Picked`] (called on the render thread: it must return
/// quickly).
pub type PickSink = Arc<dyn Fn(Picked) + Send + Sync>;

/// The sink and the ids last traced.
pub(super) struct Picking {
    sink: PickSink,
    /// Scene version and BVH builds + refits of `ids`.
    key: Option<(u64, u64)>,
    ids: Option<Arc<IdBuffer>>,
}

impl Watch {
    /// Hands the id buffer and the entities' provenance of every scene rendered to `sink` (the
    /// viewer's picking) from now on.
    pub fn set_pick_sink(&mut self, sink: PickSink) {
        self.renderer.keep_provenance(true);
        self.picking = Some(Picking {
            sink,
            key: None,
            ids: None,
        });
    }

    /// Sends the ids and provenance of the world as it is, for reload `reload`.
    pub(super) fn publish_pick(&mut self, reload: u64) {
        let Some(picking) = self.picking.as_mut() else {
            return;
        };
        let Some(provenance) = self.renderer.provenance() else {
            return;
        };
        let counters = self.renderer.counters();
        let key = (
            self.renderer.scene_version(),
            counters.bvh_builds + counters.bvh_refits,
        );
        let ids = match &picking.ids {
            Some(ids) if picking.key == Some(key) => ids.clone(),
            _ => {
                let ids = Arc::new(self.renderer.pick_ids());
                picking.key = Some(key);
                picking.ids = Some(ids.clone());
                ids
            }
        };
        (picking.sink)(Picked {
            reload,
            ids,
            provenance,
        });
    }
}
