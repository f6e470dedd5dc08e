//! Node transforms, checked to be finite and invertible, and the walk of the default scene
//! composing them.

use glam::{Affine3A, Mat3A, Mat4, Quat, Vec3, Vec3A};

use super::data::{GltfNode, GltfScene, MAX_NODE_DEPTH, MAX_NODE_INSTANCES};

/// Smallest |scale| of a node on any axis, as the RON loader's `Transform` allows.
pub(super) const MIN_SCALE: f32 = 1e-12;

/// Smallest volume of a node matrix's unit cube relative to the product of its axes' lengths
/// (1 for any rotation and scale; near 0 when the axes are nearly coplanar).
pub(super) const MIN_AXIS_VOLUME: f32 = 1e-6;

/// The node's own transform (TRS or matrix), checked to be finite and invertible, as RON's
/// `Transform` is: no scale below [`MIN_SCALE`] on any axis, a matrix's last row `0 0 0 1`
/// (glTF matrices are affine) and its axes not (nearly) coplanar.
pub(super) fn local(node: &gltf::Node) -> Result<Affine3A, String> {
    let i = node.index();
    let m = match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            let row = [matrix[0][3], matrix[1][3], matrix[2][3], matrix[3][3]];
            if row != [0.0, 0.0, 0.0, 1.0] {
                return Err(format!(
                    "node {i}: matrix's last row is {row:?}, must be [0, 0, 0, 1] (an affine transform)"
                ));
            }
            let m = Affine3A::from_mat4(Mat4::from_cols_array_2d(&matrix));
            let axes = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
            if let Some(k) = axes.iter().position(|a| a.length() < MIN_SCALE) {
                return Err(format!(
                    "node {i}: matrix scales axis {k} to zero (length below {MIN_SCALE})"
                ));
            }
            let [x, y, z] = axes.map(Vec3A::normalize);
            let volume = Mat3A::from_cols(x, y, z).determinant().abs();
            if volume < MIN_AXIS_VOLUME {
                return Err(format!(
                    "node {i}: matrix is singular (its axes are coplanar)"
                ));
            }
            m
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            if let Some(k) = scale.iter().position(|s| s.abs() < MIN_SCALE) {
                return Err(format!(
                    "node {i}: scale[{k}] is {}, must be non-zero (at least {MIN_SCALE} in size)",
                    scale[k]
                ));
            }
            Affine3A::from_scale_rotation_translation(
                Vec3::from(scale),
                Quat::from_array(rotation).normalize(),
                Vec3::from(translation),
            )
        }
    };
    // Also catches what the comparisons above let through: NaN is below nothing.
    if !m.is_finite() {
        return Err(format!("node {i}: non-finite transform"));
    }
    Ok(m)
}

/// Lists `node` and its descendants with composed transforms.
pub(super) fn walk(
    node: &gltf::Node,
    parent: Affine3A,
    depth: usize,
    scene: &mut GltfScene,
) -> Result<(), String> {
    if depth >= MAX_NODE_DEPTH {
        return Err(format!(
            "node {}: hierarchy deeper than {MAX_NODE_DEPTH} (or a cycle)",
            node.index()
        ));
    }
    let world = parent * local(node)?;
    if node.skin().is_some() {
        scene
            .warnings
            .push(format!("node {}: skin ignored", node.index()));
    }
    if scene.nodes.len() >= MAX_NODE_INSTANCES {
        return Err(format!(
            "more than {MAX_NODE_INSTANCES} node instances in the default scene"
        ));
    }
    scene.nodes.push(GltfNode {
        index: node.index(),
        name: node.name().map(str::to_owned),
        world_from_node: world,
        mesh: node.mesh().map(|m| m.index()),
        camera: node.camera().map(|c| c.index()),
        // The index was validated against the file's lights (`validate`), so the crate's
        // lookup finds it.
        light: node.light().map(|l| l.index()),
    });
    for child in node.children() {
        walk(&child, world, depth + 1, scene)?;
    }
    Ok(())
}
