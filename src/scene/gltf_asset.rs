//! What a loaded glTF file leaves in the asset store (`obj::AssetStore`'s cache), apart from
//! the loader (`gltf`), so that the store and the loader do not import each other.

use glam::Mat4;

use super::light::Light;

/// What a glTF file gives a scene besides its mesh, in the file's own coordinates (the
/// default scene's root space); an object's transform applies on top.
#[derive(Clone, Debug)]
pub(crate) struct GltfAsset {
    /// Index into the store's meshes.
    pub mesh: usize,
    pub lights: Vec<Light>,
    pub camera: Option<GltfCamera>,
}

/// A glTF camera placed by its node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GltfCamera {
    /// The camera node's world matrix (the camera looks down its −Z with +Y up).
    pub world: Mat4,
    pub projection: GltfProjection,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum GltfProjection {
    Perspective {
        yfov_rad: f32,
        znear: f32,
        /// `None`: an infinite projection.
        zfar: Option<f32>,
    },
    Orthographic {
        /// Half the view's height.
        ymag: f32,
        znear: f32,
        zfar: f32,
    },
}
