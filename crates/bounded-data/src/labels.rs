//! Labelled loaders: ground-truth classes from colours or from a class property.
//!
//! Colours and normals of labelled files are only ever read as labels, never as features.
//!
//! | convention | sharp | non-edge | other |
//! |---|---|---|---|
//! | [`Convention::Pcednet`] | (168,0,0), (255,0,0) | white | smooth edge (255,196,93) configurable, default non-edge |
//! | [`Convention::Bazazian`] | red (255,0,0), yellow (255,255,0) | white | |
//! | [`Convention::ClassProperty`] | `class`/`scalar_class`/`label` = 1 | 0 | 2 boundary |
//!
//! Without such a property, [`Convention::ClassProperty`] reads a LAS output's Classification
//! when it holds only BoundED's default codes (1 non-edge, 64 sharp, 65 boundary).
//!
//! Any other colour or value is an error naming the point, never a silent guess.

use crate::las::{CODE_BOUNDARY, CODE_NON_EDGE, CODE_SHARP};
use crate::table::{Column, PointTable};
use crate::{DataError, LabelledCloud};
use bounded_geom::Class;
use std::path::Path;

/// How the labels of a file are encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Convention {
    /// PCEDNet evaluation clouds: colour-coded, smooth edges mapped to `smooth_edge`
    /// (the paper counts them as [`Class::NonEdge`]).
    Pcednet {
        /// The class of smooth-edge points (255,196,93).
        smooth_edge: Class,
    },
    /// Bazazian et al. clouds: red or yellow edges (sharp), white non-edge.
    Bazazian,
    /// An integer `class` or `label` property with the [`Class`] codes 0/1/2.
    ClassProperty,
}

impl Convention {
    /// The PCEDNet convention as in the paper (smooth edges are non-edge).
    pub const PCEDNET: Convention = Convention::Pcednet {
        smooth_edge: Class::NonEdge,
    };
}

impl std::fmt::Display for Convention {
    /// How the labels are stored, as error messages name it.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Convention::Pcednet { .. } => "PCEDNet label colours",
            Convention::Bazazian => "Bazazian label colours",
            Convention::ClassProperty => "a class property",
        })
    }
}

/// Reads `path` (any supported format) and derives its labels by `convention`.
pub fn load(path: &Path, convention: Convention) -> Result<LabelledCloud, DataError> {
    let table = crate::format::read(path)?;
    from_table(table, convention, path)
}

/// Derives the labels of an already-read `table`; `path` names it in errors.
pub fn from_table(
    table: PointTable,
    convention: Convention,
    path: &Path,
) -> Result<LabelledCloud, DataError> {
    let labels = match convention {
        Convention::Pcednet { smooth_edge } => by_colour(&table, |rgb| match rgb {
            [168, 0, 0] | [255, 0, 0] => Some(Class::Sharp),
            [255, 196, 93] => Some(smooth_edge),
            [255, 255, 255] => Some(Class::NonEdge),
            _ => None,
        }),
        Convention::Bazazian => by_colour(&table, |rgb| match rgb {
            [255, 0, 0] | [255, 255, 0] => Some(Class::Sharp),
            [255, 255, 255] => Some(Class::NonEdge),
            _ => None,
        }),
        Convention::ClassProperty => by_class(&table),
    }
    .map_err(|what| DataError::Labels {
        path: path.to_path_buf(),
        what: format!("{what} (expected {convention})"),
    })?;
    Ok(LabelledCloud {
        cloud: table.cloud,
        labels,
    })
}

fn by_colour(
    table: &PointTable,
    class_of: impl Fn([u16; 3]) -> Option<Class>,
) -> Result<Vec<Class>, String> {
    let channel = |name: &str| {
        table
            .property(name)
            .ok_or_else(|| format!("no '{name}' colour property"))
    };
    let rgb = [channel("red")?, channel("green")?, channel("blue")?];
    (0..table.len())
        .map(|i| {
            let value = rgb.map(|c| c.get_f64(i));
            let colour = value.map(|v| v as u16);
            if value.iter().zip(colour).all(|(&v, c)| v == f64::from(c)) {
                class_of(colour)
            } else {
                None
            }
            .ok_or_else(|| format!("point {i} has colour {value:?}, which is not a label colour"))
        })
        .collect()
}

/// The column [`Convention::ClassProperty`] reads: `class`, else `scalar_class` (the name
/// annotated PLY and text outputs give it for CloudCompare), else `label`.
pub fn class_column(table: &PointTable) -> Option<&Column> {
    ["class", "scalar_class", "label"]
        .into_iter()
        .find_map(|name| table.property(name))
}

fn by_class(table: &PointTable) -> Result<Vec<Class>, String> {
    let Some(column) = class_column(table) else {
        return by_las_codes(table).ok_or_else(|| {
            "no 'class', 'scalar_class' or 'label' property, nor a LAS Classification of \
             only BoundED's codes"
                .into()
        });
    };
    (0..table.len())
        .map(|i| {
            let v = column.get_f64(i);
            (v.fract() == 0.0 && (0.0..=2.0).contains(&v))
                .then(|| Class::from_code(v as u8))
                .flatten()
                .ok_or_else(|| format!("point {i} has class {v}; expected 0, 1 or 2"))
        })
        .collect()
}

/// The classes of a LAS output whose Classification holds only BoundED's default codes
/// ([`CODE_NON_EDGE`], [`CODE_SHARP`], [`CODE_BOUNDARY`]); `None` otherwise.
fn by_las_codes(table: &PointTable) -> Option<Vec<Class>> {
    let column = table.property("classification")?;
    (0..table.len())
        .map(|i| match column.get_f64(i) {
            v if v == f64::from(CODE_NON_EDGE) => Some(Class::NonEdge),
            v if v == f64::from(CODE_SHARP) => Some(Class::Sharp),
            v if v == f64::from(CODE_BOUNDARY) => Some(Class::Boundary),
            _ => None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::Property;
    use bounded_geom::PointCloud;

    fn table(colours: &[[u8; 3]]) -> PointTable {
        let n = colours.len();
        let cloud = PointCloud::from_iter_f64(n, |i| [i as f64, 0.0, 0.0]).unwrap();
        let mut t = PointTable::new(cloud);
        for (k, name) in ["red", "green", "blue"].into_iter().enumerate() {
            let c = Column::U8(colours.iter().map(|c| c[k]).collect());
            t.set_property(Property::new(name, c));
        }
        t
    }

    #[test]
    fn pcednet_colours_with_configurable_smooth_edges() {
        let t = table(&[[168, 0, 0], [255, 0, 0], [255, 196, 93], [255, 255, 255]]);
        let p = Path::new("t.ply");
        let l = from_table(t.clone(), Convention::PCEDNET, p).unwrap();
        use Class::*;
        assert_eq!(l.labels, [Sharp, Sharp, NonEdge, NonEdge]);
        let smooth_sharp = Convention::Pcednet { smooth_edge: Sharp };
        let l = from_table(t, smooth_sharp, p).unwrap();
        assert_eq!(l.labels, [Sharp, Sharp, Sharp, NonEdge]);
    }

    #[test]
    fn bazazian_colours_and_unknown_colour_error() {
        let p = Path::new("b.ply");
        let t = table(&[[255, 255, 0], [255, 0, 0], [255, 255, 255]]);
        let l = from_table(t, Convention::Bazazian, p).unwrap();
        assert_eq!(l.class_counts(), [1, 2, 0]);
        let e = from_table(
            table(&[[255, 255, 255], [1, 2, 3]]),
            Convention::Bazazian,
            p,
        );
        let msg = e.unwrap_err().to_string();
        assert!(
            msg.contains("b.ply")
                && msg.contains("point 1")
                && msg.contains("[1.0, 2.0, 3.0]")
                && msg.ends_with("(expected Bazazian label colours)"),
            "{msg}"
        );
    }

    #[test]
    fn class_or_label_property() {
        let p = Path::new("c.ply");
        let mut t = table(&[[0, 0, 0]; 3]);
        t.set_property(Property::new("label", Column::I32(vec![2, 0, 1])));
        let l = from_table(t.clone(), Convention::ClassProperty, p).unwrap();
        assert_eq!(l.labels, [Class::Boundary, Class::NonEdge, Class::Sharp]);
        t.set_property(Property::new("class", Column::F32(vec![0.0, 3.0, 1.0])));
        let msg = from_table(t, Convention::ClassProperty, p)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("point 1 has class 3"), "{msg}");
    }

    #[test]
    fn las_classification_of_our_codes_only() {
        let p = Path::new("c.las");
        let mut t = table(&[[0, 0, 0]; 3]);
        t.set_property(Property::new("classification", Column::U8(vec![65, 1, 64])));
        let l = from_table(t.clone(), Convention::ClassProperty, p).unwrap();
        assert_eq!(l.labels, [Class::Boundary, Class::NonEdge, Class::Sharp]);
        // Ground (2) is not one of ours: no guess.
        t.set_property(Property::new("classification", Column::U8(vec![65, 2, 64])));
        let msg = from_table(t, Convention::ClassProperty, p)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("nor a LAS Classification"), "{msg}");
    }
}
