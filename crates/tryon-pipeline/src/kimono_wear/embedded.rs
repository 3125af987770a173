//! The worn shapes of data/kimono built into the library (by build.rs, which takes the files
//! that exist), so `tryon kimono` and kimono scenes fit on worn targets wherever they run.

include!(concat!(env!("OUT_DIR"), "/kimono_shapes.rs"));

/// The OBJ text of the built-in shape `name`.
pub fn shape(name: &str) -> Option<&'static str> {
    SHAPES.iter().find(|s| s.0 == name).map(|s| s.1)
}

/// [`shape`] as [`crate::kimono::Targets::Worn`] takes it.
pub fn shape_text(name: &str) -> Option<String> {
    shape(name).map(str::to_string)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kimono_wear::store::{family_wearers, shape_name};

    #[test]
    fn every_wearer_of_the_family_has_its_worn_shape_built_in() {
        for w in family_wearers() {
            let name = shape_name(&w);
            assert!(shape(&name).is_some(), "{name} is not in data/kimono");
        }
    }
}
