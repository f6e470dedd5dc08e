//! `EXT_mesh_gpu_instancing`: a node whose mesh is drawn once per element of its
//! `TRANSLATION`, `ROTATION` and `SCALE` accessors. Each instance becomes one more listing of the
//! node, placed by the node's world transform times the instance's `T · R · S` (the extension's
//! order), so the placement instances the one mesh (one bottom-level BVH) as it does a node
//! reached through several parents.

use glam::{Affine3A, Quat, Vec3};
use gltf::json::Value;

use super::accessors::read_floats;
use super::data::{GltfNode, GltfScene, MAX_NODE_INSTANCES, SharedBytes};
use super::nodes::MIN_SCALE;

/// The extension's name.
pub(super) const NAME: &str = "EXT_mesh_gpu_instancing";

/// Replaces every listed node that has the extension (and a mesh) by one listing per instance.
/// The listings of the scene stay within [`MAX_NODE_INSTANCES`], checked before the instances'
/// transforms are allocated.
pub(super) fn expand(
    doc: &gltf::Document,
    buffers: &[SharedBytes],
    scene: &mut GltfScene,
) -> Result<(), String> {
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let instanced = |n: &GltfNode| {
        n.mesh.is_some()
            && nodes
                .get(n.index)
                .and_then(|g| g.extension_value(NAME))
                .is_some()
    };
    if !scene.nodes.iter().any(instanced) {
        return Ok(());
    }
    let listed = std::mem::take(&mut scene.nodes);
    let mut out = Vec::with_capacity(listed.len());
    for (k, node) in listed.iter().enumerate() {
        let ext = match nodes.get(node.index).and_then(|g| g.extension_value(NAME)) {
            Some(ext) if node.mesh.is_some() => ext,
            _ => {
                out.push(node.clone());
                continue;
            }
        };
        // What the listings still to come need, one each at least.
        let room = MAX_NODE_INSTANCES.saturating_sub(out.len() + (listed.len() - k - 1));
        let what = format!("node {}: extensions.{NAME}", node.index);
        let locals = instances(doc, ext, buffers, room).map_err(|e| format!("{what}: {e}"))?;
        out.extend(locals.into_iter().map(|local| GltfNode {
            world_from_node: node.world_from_node * local,
            ..node.clone()
        }));
    }
    scene.nodes = out;
    Ok(())
}

/// The instances' transforms `T · R · S` of one node's extension value, at most `room` of them.
fn instances(
    doc: &gltf::Document,
    ext: &Value,
    buffers: &[SharedBytes],
    room: usize,
) -> Result<Vec<Affine3A>, String> {
    let Some(Value::Object(attributes)) = ext.get("attributes") else {
        return Err("attributes is missing or not an object".into());
    };
    let accessor = |name: &str| -> Result<Option<gltf::Accessor>, String> {
        let Some(v) = attributes.get(name) else {
            return Ok(None);
        };
        let index = v
            .as_u64()
            .ok_or_else(|| format!("attributes.{name} is {v}, must be an accessor index"))?;
        let acc = usize::try_from(index)
            .ok()
            .and_then(|i| doc.accessors().nth(i))
            .ok_or_else(|| format!("attributes.{name}: accessor {index} does not exist"))?;
        Ok(Some(acc))
    };
    let (t, r, s) = (
        accessor("TRANSLATION")?,
        accessor("ROTATION")?,
        accessor("SCALE")?,
    );
    let counts: Vec<usize> = [&t, &r, &s]
        .iter()
        .filter_map(|a| a.as_ref().map(gltf::Accessor::count))
        .collect();
    let Some(&count) = counts.first() else {
        return Err("none of TRANSLATION, ROTATION, SCALE is given".into());
    };
    if counts.iter().any(|&c| c != count) {
        return Err(format!(
            "TRANSLATION, ROTATION and SCALE have different counts {counts:?}"
        ));
    }
    if count > room {
        return Err(format!(
            "{count} instances; at most {MAX_NODE_INSTANCES} node instances are listed per file"
        ));
    }
    let read = |acc: &Option<gltf::Accessor>, dims: usize| -> Result<Option<Vec<f32>>, String> {
        acc.as_ref()
            .map(|a| read_floats(a, dims, buffers))
            .transpose()
    };
    let (t, r, s) = (read(&t, 3)?, read(&r, 4)?, read(&s, 3)?);
    (0..count)
        .map(|i| {
            let translation = t.as_ref().map_or(Vec3::ZERO, |t| Vec3::from_slice(&t[3 * i..]));
            let rotation = r
                .as_ref()
                .map_or(Quat::IDENTITY, |r| Quat::from_slice(&r[4 * i..]).normalize());
            let scale = s.as_ref().map_or(Vec3::ONE, |s| Vec3::from_slice(&s[3 * i..]));
            if let Some(k) = scale.to_array().iter().position(|c| c.abs() < MIN_SCALE) {
                return Err(format!(
                    "instance {i}: scale[{k}] is {}, must be non-zero (at least {MIN_SCALE} in size)",
                    scale[k]
                ));
            }
            let m = Affine3A::from_scale_rotation_translation(scale, rotation, translation);
            // Also catches a zero or non-finite rotation (normalising it gives NaN).
            if !m.is_finite() {
                return Err(format!("instance {i}: non-finite transform"));
            }
            Ok(m)
        })
        .collect()
}
