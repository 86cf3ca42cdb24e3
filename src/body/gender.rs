//! The two body-model genders.

use crate::error::{Error, Result};

/// Which of the two shape spaces of a [`super::BodyModel`] to use. The numeric values are those
/// of the C API (`0` female, `1` male) and the order in which the `.skbm` file stores them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Gender {
    /// Female shape space (MakeHuman gender slider 0).
    Female = 0,
    /// Male shape space (MakeHuman gender slider 1).
    Male = 1,
}

impl Gender {
    /// Both genders in storage order.
    pub const ALL: [Gender; 2] = [Gender::Female, Gender::Male];

    /// The gender with C-API number `index` (0 female, 1 male); any other number is an
    /// [`Error::OutOfRange`].
    pub fn from_index(index: u32) -> Result<Gender> {
        match index {
            0 => Ok(Gender::Female),
            1 => Ok(Gender::Male),
            _ => {
                Err(Error::OutOfRange { name: "gender", detail: format!("{index} (expected 0 = female or 1 = male)") })
            }
        }
    }

    /// Parses "f", "female", "m" or "male" (ASCII case-insensitive).
    pub fn parse(text: &str) -> Result<Gender> {
        match text.to_ascii_lowercase().as_str() {
            "f" | "female" => Ok(Gender::Female),
            "m" | "male" => Ok(Gender::Male),
            _ => Err(Error::OutOfRange { name: "gender", detail: format!("{text:?} (expected f, female, m or male)") }),
        }
    }

    /// Storage / C-API index: 0 female, 1 male.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Lower-case English name.
    pub fn name(self) -> &'static str {
        match self {
            Gender::Female => "female",
            Gender::Male => "male",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gender_round_trips_and_rejects_unknown() {
        for g in Gender::ALL {
            assert_eq!(Gender::from_index(g.index() as u32).unwrap(), g);
            assert_eq!(Gender::parse(g.name()).unwrap(), g);
        }
        assert_eq!(Gender::parse("M").unwrap(), Gender::Male);
        assert!(matches!(Gender::from_index(2), Err(Error::OutOfRange { name: "gender", .. })));
        assert!(matches!(Gender::parse("x"), Err(Error::OutOfRange { .. })));
    }
}
