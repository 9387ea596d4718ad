//! Direct light: shadow-map views per light (spot: perspective map; point: six cube faces or
//! two paraboloid hemispheres; directional: an orthographic map fitted to the scene), after
//! seeds/001 (digest_001_004.md).

mod shadow;

pub use shadow::{
    shadow_views, LightShadows, PointShadow, ShadowProjection, ShadowSettings, ShadowView,
};
