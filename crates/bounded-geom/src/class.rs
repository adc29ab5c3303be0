/// The three classes of BoundED, with their stable integer codes.
///
/// The codes are written to files (`class` property, LAS Classification mapping) and
/// index the network's outputs, so they never change.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum Class {
    /// A point on a smooth surface (smooth edges count as non-edge).
    NonEdge = 0,
    /// A point on a sharp crease of the surface.
    Sharp = 1,
    /// A point on the border of an open surface, or on a very thin structure.
    Boundary = 2,
}

impl Class {
    /// All classes, in code order.
    pub const ALL: [Class; 3] = [Class::NonEdge, Class::Sharp, Class::Boundary];

    /// Number of entries of each class in `classes`, indexed by code.
    pub fn counts(classes: &[Class]) -> [usize; 3] {
        let mut counts = [0; 3];
        for &class in classes {
            counts[class as usize] += 1;
        }
        counts
    }

    /// The integer codes of `classes`, as the classifier and the metrics take them.
    pub fn codes(classes: &[Class]) -> Vec<u8> {
        classes.iter().map(|&c| c as u8).collect()
    }

    /// The class with code `code`, if any.
    pub fn from_code(code: u8) -> Option<Class> {
        Class::ALL.get(usize::from(code)).copied()
    }

    /// Lower-case name, as used in reports and model files.
    pub const fn name(self) -> &'static str {
        match self {
            Class::NonEdge => "non-edge",
            Class::Sharp => "sharp",
            Class::Boundary => "boundary",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_codes_of_a_list() {
        let classes = [Class::Sharp, Class::NonEdge, Class::Sharp, Class::Boundary];
        assert_eq!(Class::counts(&classes), [1, 2, 1]);
        assert_eq!(Class::codes(&classes), vec![1, 0, 1, 2]);
    }

    #[test]
    fn codes_round_trip() {
        for c in Class::ALL {
            assert_eq!(Class::from_code(c as u8), Some(c));
        }
        assert_eq!(Class::from_code(3), None);
    }
}
