//! `voxgi devices`: the Vulkan devices and whether voxgi can use them.

use super::{out, CliError};
use std::io::Write;

/// Prints every device and the default choice.
pub fn devices(out: &mut dyn Write) -> Result<(), CliError> {
    out!(out, "{}", crate::vk::describe_devices()?);
    Ok(())
}
