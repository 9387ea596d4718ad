//! Files of the project found from any directory: a relative path that does not exist from
//! the current directory is looked up under the project's root (the directory this binary
//! was built from), so that `voxgi sweep cornell` run elsewhere still finds
//! `assets/references/cornell_gi.exr`, and `voxgi render assets/scenes/cornell_bunny.toml`
//! its scene file. Paths that exist where they are given always win; a path found in neither
//! place is returned unchanged, so the error that follows names it as the user gave it.

use std::path::{Path, PathBuf};

/// The project's root: where `Cargo.toml` and `assets/` were when this binary was built.
pub fn project_root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `path` if it exists (or is absolute); else the same relative path under
/// [`project_root`] if that exists; else `path` unchanged.
pub fn find(path: &Path) -> PathBuf {
    find_under(path, project_root())
}

fn find_under(path: &Path, root: &Path) -> PathBuf {
    if path.is_absolute() || path.exists() {
        return path.to_owned();
    }
    let under_root = root.join(path);
    if under_root.exists() {
        under_root
    } else {
        path.to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_relative_path_falls_back_to_the_project_root() {
        let reference = Path::new("assets/references/cornell_gi.exr");
        let found = find(reference);
        assert!(found.exists(), "{}", found.display());
        // A root that has nothing: the path comes back as given, for the error to name it.
        let nowhere = std::env::temp_dir().join("voxgi-no-such-root");
        let missing = Path::new("assets/no-such-file.exr");
        assert_eq!(find_under(missing, &nowhere), missing);
        assert_eq!(find(missing), missing);
        // An absolute path is never rewritten.
        let abs = nowhere.join("x.exr");
        assert_eq!(find(&abs), abs);
    }
}
