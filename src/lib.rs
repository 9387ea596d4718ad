//! voxgi: a Vulkan-native real-time global-illumination renderer (voxel GI after Thiedemann
//! 2010, on a render graph after Oetke 2017). `docs/ARCHITECTURE.md` is the map of the code.
//!
//! `vk` is the only module that calls Vulkan; `graph` derives every barrier; the remaining
//! modules are safe Rust.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

#[forbid(unsafe_code)]
pub mod app;
#[forbid(unsafe_code)]
pub mod assets;
#[forbid(unsafe_code)]
pub mod bench;
#[forbid(unsafe_code)]
pub mod cli;
pub mod demo;
#[forbid(unsafe_code)]
pub mod eval;
#[forbid(unsafe_code)]
pub mod export;
#[forbid(unsafe_code)]
pub mod gi;
#[forbid(unsafe_code)]
pub mod graph;
#[forbid(unsafe_code)]
pub mod imaging;
#[forbid(unsafe_code)]
pub mod light;
pub mod limits;
#[forbid(unsafe_code)]
pub mod panel_keys;
#[forbid(unsafe_code)]
pub mod post;
#[forbid(unsafe_code)]
pub mod profile;
#[forbid(unsafe_code)]
pub mod render;
#[forbid(unsafe_code)]
pub mod scene;
#[forbid(unsafe_code)]
pub mod stats;
#[forbid(unsafe_code)]
pub mod tune;
pub mod vk;
#[forbid(unsafe_code)]
pub mod voxel;
