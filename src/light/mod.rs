//! Direct light: shadow-map views per light (spot: perspective map; point: six cube faces;
//! directional: an orthographic map fitted to the scene), after seeds/001 (digest_001_004.md).

mod shadow;

pub use shadow::{shadow_views, LightShadows, ShadowSettings, ShadowView};
