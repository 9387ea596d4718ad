//! Finding a scene object from what a user typed (`--object NAME_OR_INDEX`, the viewer's
//! atlas picker).

use super::Scene;

/// No object of the scene matches a selector. The message lists the objects there are, so the
/// user can pick one.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the scene has no object '{selector}'; pass --object with one of: {objects}")]
pub struct NoSuchObject {
    /// What was asked for: a name or an index.
    pub selector: String,
    /// Every object as `index 'name'`, comma-separated, in the scene's order.
    pub objects: String,
}

impl NoSuchObject {
    /// The error for `selector` in `scene`.
    pub fn new(scene: &Scene, selector: &str) -> Self {
        let objects: Vec<String> = scene
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| format!("{i} '{}'", o.name))
            .collect();
        Self {
            selector: selector.to_owned(),
            objects: objects.join(", "),
        }
    }
}

impl Scene {
    /// The index of the object that `selector` names: its name, else its index in the scene
    /// file's order. A name wins over an index, so an object named `"2"` is found by name.
    pub fn find_object(&self, selector: &str) -> Result<usize, NoSuchObject> {
        if let Some(i) = self.objects.iter().position(|o| o.name == selector) {
            return Ok(i);
        }
        match selector.parse::<usize>() {
            Ok(i) if i < self.objects.len() => Ok(i),
            _ => Err(NoSuchObject::new(self, selector)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin;
    use std::path::Path;

    fn cornell() -> Scene {
        builtin("cornell").expect("the built-in Cornell box")
    }

    #[test]
    fn objects_are_found_by_name_and_by_index() {
        let s = cornell();
        let names: Vec<&str> = s.objects.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["walls", "short_block", "tall_block"]);
        assert_eq!(s.find_object("tall_block"), Ok(2));
        assert_eq!(s.find_object("walls"), Ok(0));
        assert_eq!(s.find_object("1"), Ok(1));
    }

    #[test]
    fn a_missing_object_names_the_selector_and_lists_the_objects() {
        let s = cornell();
        let err = s.find_object("teapot").expect_err("no teapot in the box");
        assert_eq!(
            err.to_string(),
            "the scene has no object 'teapot'; pass --object with one of: \
             0 'walls', 1 'short_block', 2 'tall_block'"
        );
        // Three objects: indices 0..=2 only; no negative or partial matches either.
        for selector in ["3", "-1", "tall", ""] {
            let err = s.find_object(selector).expect_err(selector);
            assert_eq!(err.selector, selector);
        }
    }

    #[test]
    fn a_name_wins_over_an_index() {
        let toml = "[camera]\nposition = [0.0, 0.0, -3.0]\ntarget = [0.0, 0.0, 0.0]\n\
                    fov_y_deg = 40.0\n\n\
                    [[lights]]\nkind = \"point\"\nposition = [0.0, 2.0, 0.0]\n\
                    intensity_w_sr = [1.0, 1.0, 1.0]\n\n\
                    [[objects]]\nname = \"box\"\nbuiltin = \"cube\"\n\n\
                    [[objects]]\nname = \"0\"\nbuiltin = \"cube\"\n";
        let s = Scene::from_toml_str(toml, Path::new("<test>"), Path::new("."))
            .expect("a two-cube scene");
        assert_eq!(s.find_object("0"), Ok(1), "the object named 0, not index 0");
        assert_eq!(s.find_object("1"), Ok(1));
        assert_eq!(s.find_object("box"), Ok(0));
    }
}
