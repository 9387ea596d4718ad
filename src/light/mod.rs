//! Direct light: shadow-map views per light (spot: perspective map; point: six cube faces or
//! two paraboloid hemispheres; directional: an orthographic map fitted to the scene, plus
//! cascades fitted to the view frustum for the camera's direct light, `cascade`; area
//! lights: one paraboloid hemisphere per sample, `area`), after
//! Dachsbacher 2014 (KIT lecture notes, "Echtzeit-Schattenverfahren", part 3).

pub mod area;
pub mod cascade;
mod shadow;

pub use crate::scene::{AreaShadow, PointShadow, ShadowSettings, DEFAULT_CASCADES};
pub use shadow::{shadow_views, LightShadows, ShadowProjection, ShadowView};
