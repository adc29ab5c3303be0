//! Annotated outputs: the detection results added to every input property, chosen by
//! [`AnnotateOptions`], and how a later run recognises them in its input.
//!
//! | property | type | meaning |
//! |---|---|---|
//! | `class` | uint8 (float32 in PCD, which PCL filters on) | 0 non-edge, 1 sharp edge, 2 boundary |
//! | `p_nonedge`, `p_sharp`, `p_boundary` | float32 | class probabilities |
//! | `red`, `green`, `blue` | uint8 | class colours: sharp (255,0,0), boundary (0,255,0), non-edge (160,160,160), by [`Colours`] |
//!
//! PLY and text outputs name them by [`Flavour`]; LAS outputs put the class where
//! [`ClassTarget`] says (see [`crate::las`]).
//!
//! Nothing the input carried is lost by default: its colours stay ([`Colours::KeepInput`]),
//! a meaningful LAS Classification stays ([`ClassTarget::Auto`]), and an input property whose
//! name an annotation column takes is kept as `input_<name>` (a LAS Classification replaced
//! by class codes becomes `input_classification`).
//!
//! Running on an annotated output replaces that run's results instead of adding a second set:
//! a table holding the three probability columns (under any flavour's names) is taken as an
//! annotated output; its class and probability columns, `quality` (when it repeats
//! `p_sharp`), `class_red`/`class_green`/`class_blue`, colours that are class colours at every
//! point, and a Classification holding class codes (when there is no class column) are left
//! out, and `input_classification` becomes `classification` again. The second output is then
//! the first one again.

use crate::DataError;
use crate::format::{Format, class_colour, write_to, write_view};
use crate::las::{CODE_BOUNDARY, CODE_NON_EDGE, CODE_SHARP};
use crate::table::{Column, PointTable, Property};
use bounded_geom::Class;
use rayon::prelude::*;
use std::borrow::Cow;
use std::io::Write;
use std::path::Path;

/// How [`write_annotated_with`] writes the results; the default keeps everything the input
/// carried.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct AnnotateOptions {
    /// Where the class goes in LAS and LAZ outputs.
    pub class_to: ClassTarget,
    /// Whether class colours replace, join or give way to the input's colours.
    pub colours: Colours,
    /// The property names of PLY and text outputs.
    pub flavour: Flavour,
}

/// Where a LAS or LAZ output holds the class (other formats always have a `class` column).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ClassTarget {
    /// [`ClassTarget::Classification`] with the default codes when the input has no
    /// Classification or one of only codes 0 ("never classified") and 1 ("unclassified"),
    /// else [`ClassTarget::Extra`]: ground, building or vegetation classes are never replaced.
    #[default]
    Auto,
    /// The Classification field, with these codes; an input Classification holding any code
    /// other than 0 and 1 is kept as the Extra Bytes field `input_classification`.
    Classification(ClassCodes),
    /// An Extra Bytes field `class` (0, 1, 2); the Classification field stays the input's.
    Extra,
}

/// The LAS Classification codes of the three classes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ClassCodes {
    /// Code of non-edge points (default 1, "unclassified").
    pub non_edge: u8,
    /// Code of sharp-edge points (default 64, the first user-definable code).
    pub sharp: u8,
    /// Code of boundary points (default 65, user-definable).
    pub boundary: u8,
}

impl Default for ClassCodes {
    fn default() -> Self {
        ClassCodes {
            non_edge: CODE_NON_EDGE,
            sharp: CODE_SHARP,
            boundary: CODE_BOUNDARY,
        }
    }
}

impl ClassCodes {
    fn of(self, class: Class) -> u8 {
        match class {
            Class::NonEdge => self.non_edge,
            Class::Sharp => self.sharp,
            Class::Boundary => self.boundary,
        }
    }
}

/// What happens to colours.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Colours {
    /// The input's `red`, `green`, `blue` stay; class colours fill them only when the input
    /// has none (so a viewer shows the classes of a colourless cloud and the scan colours of a
    /// coloured one).
    #[default]
    KeepInput,
    /// Class colours in `red`, `green`, `blue`; the input's colours are not written.
    Replace,
    /// Class colours as `class_red`, `class_green`, `class_blue` (uint8), beside the input's
    /// colours, if any.
    Add,
}

/// Property names and extras of PLY and text outputs, for the desktop tool that opens them.
/// LAS, PCD and E57 outputs always use the plain names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Flavour {
    /// `scalar_class`, `scalar_p_nonedge`, `scalar_p_sharp`, `scalar_p_boundary`: CloudCompare
    /// loads `scalar_` properties (PLY) and columns whose header name holds `SCALAR` (text) as
    /// scalar fields without asking, named without the prefix; every other reader takes them
    /// as ordinary properties. CSV headers start with `//`, as in CloudCompare's own exports,
    /// since its loader reads names from no other header line (checked with CloudCompare
    /// 2.11's command line).
    #[default]
    CloudCompare,
    /// `class`, `p_nonedge`, `p_sharp`, `p_boundary`.
    Plain,
    /// The plain names and `quality` (float32, a copy of `p_sharp`), the one scalar MeshLab
    /// loads from PLY (as vertex quality).
    MeshLab,
}

impl std::str::FromStr for ClassTarget {
    type Err = String;

    /// `auto`, `extra`, `classification` (the default codes) or
    /// `classification:NON_EDGE,SHARP,BOUNDARY` (three codes 0-255), as the CLI spells them.
    fn from_str(s: &str) -> Result<Self, String> {
        match s.split_once(':') {
            None if s == "auto" => Ok(ClassTarget::Auto),
            None if s == "extra" => Ok(ClassTarget::Extra),
            None if s == "classification" => Ok(ClassTarget::Classification(ClassCodes::default())),
            Some(("classification", codes)) => {
                let codes: Vec<u8> = (codes.split(','))
                    .map(|c| c.trim().parse::<u8>())
                    .collect::<Result<_, _>>()
                    .map_err(|_| {
                        format!("{codes:?}: expected three codes 0-255, such as 1,64,65")
                    })?;
                match codes[..] {
                    [non_edge, sharp, boundary] => Ok(ClassTarget::Classification(ClassCodes {
                        non_edge,
                        sharp,
                        boundary,
                    })),
                    _ => Err(format!(
                        "{} codes given, three needed (non-edge, sharp, boundary)",
                        codes.len()
                    )),
                }
            }
            _ => Err(format!(
                "{s:?}: expected auto, extra, classification or classification:NON_EDGE,SHARP,BOUNDARY"
            )),
        }
    }
}

impl std::str::FromStr for Colours {
    type Err = String;

    /// `keep`, `replace` or `add`.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "keep" => Ok(Colours::KeepInput),
            "replace" => Ok(Colours::Replace),
            "add" => Ok(Colours::Add),
            _ => Err(format!("{s:?}: expected keep, replace or add")),
        }
    }
}

impl std::str::FromStr for Flavour {
    type Err = String;

    /// `cloudcompare`, `plain` or `meshlab`.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "cloudcompare" => Ok(Flavour::CloudCompare),
            "plain" => Ok(Flavour::Plain),
            "meshlab" => Ok(Flavour::MeshLab),
            _ => Err(format!("{s:?}: expected cloudcompare, plain or meshlab")),
        }
    }
}

/// The class and probability names of each flavour: plain, then CloudCompare's.
const NAMES: [[&str; 4]; 2] = [
    ["class", "p_nonedge", "p_sharp", "p_boundary"],
    [
        "scalar_class",
        "scalar_p_nonedge",
        "scalar_p_sharp",
        "scalar_p_boundary",
    ],
];
/// MeshLab's vertex quality, a copy of `p_sharp`.
const QUALITY: &str = "quality";
const RGB: [&str; 3] = ["red", "green", "blue"];
const CLASS_RGB: [&str; 3] = ["class_red", "class_green", "class_blue"];
const CLASSIFICATION: &str = "classification";
const INPUT_CLASSIFICATION: &str = "input_classification";

impl Flavour {
    /// The class and probability names in `format`.
    fn names(self, format: Format) -> [&'static str; 4] {
        match (self, format) {
            (Flavour::CloudCompare, Format::Ply | Format::Xyz(_)) => NAMES[1],
            _ => NAMES[0],
        }
    }
}

/// Writes `table` with the detection results and default [`AnnotateOptions`] (see
/// [`write_annotated_with`]).
pub fn write_annotated(
    path: &Path,
    table: &PointTable,
    classes: &[Class],
    probabilities: &[[f32; 3]],
) -> Result<(), DataError> {
    write_annotated_with(
        path,
        table,
        classes,
        probabilities,
        &AnnotateOptions::default(),
    )
}

/// Writes `table` with the detection results as `options` say (see the module
/// documentation), in the format named by `path`'s extension. A previous run's results in
/// `table` are replaced, not repeated.
///
/// `classes` and `probabilities` must have one entry per point.
pub fn write_annotated_with(
    path: &Path,
    table: &PointTable,
    classes: &[Class],
    probabilities: &[[f32; 3]],
    options: &AnnotateOptions,
) -> Result<(), DataError> {
    let format = Format::from_path(path)?;
    let choices = Choices::of(table);
    let properties = annotated(
        path,
        format,
        table,
        classes,
        probabilities,
        options,
        choices,
    )?;
    write_view(path, &annotated_view(table, &properties, options))
}

/// Writes a LAS or LAZ output with the detection results like [`write_annotated_with`],
/// chunk by chunk, atomically: a cloud too large to hold, read with
/// [`crate::las::read_chunks`]. `chunks` gets a function that writes one chunk (its table,
/// classes and probabilities) and calls it for each in order; `choices` are
/// [`Choices::of`] every chunk, merged, so that the output is the one the whole table
/// would give.
pub fn write_annotated_chunks(
    path: &Path,
    options: &AnnotateOptions,
    choices: Choices,
    chunks: impl FnOnce(
        &mut dyn FnMut(&PointTable, &[Class], &[[f32; 3]]) -> Result<(), DataError>,
    ) -> Result<(), DataError>,
) -> Result<(), DataError> {
    let format = Format::from_path(path)?;
    let Format::Las { compressed } = format else {
        return Err(DataError::InvalidOutput {
            path: path.to_path_buf(),
            what: "a cloud labelled in blocks is written as .las or .laz".into(),
        });
    };
    bounded_geom::atomic::write_with(path, |file: &mut std::fs::File| {
        let file = file.try_clone().map_err(|e| DataError::io(path, e))?;
        let out = std::io::BufWriter::with_capacity(1 << 20, file);
        let mut writer = crate::las::ChunkWriter::new(out, compressed, path);
        chunks(&mut |table, classes, probabilities| {
            let properties = annotated(
                path,
                format,
                table,
                classes,
                probabilities,
                options,
                choices,
            )?;
            writer.write(&annotated_view(table, &properties, options))
        })?;
        let out = writer.finish()?;
        out.into_inner()
            .map_err(|e| DataError::io(path, e.into_error()))
            .map(drop)
    })
}

/// Writes `table` with the detection results like [`write_annotated_with`], in `format` to
/// `out` (standard output, say); `name` names the output in errors.
pub fn write_annotated_to(
    out: impl Write,
    format: Format,
    name: &Path,
    table: &PointTable,
    classes: &[Class],
    probabilities: &[[f32; 3]],
    options: &AnnotateOptions,
) -> Result<(), DataError> {
    let choices = Choices::of(table);
    let properties = annotated(
        name,
        format,
        table,
        classes,
        probabilities,
        options,
        choices,
    )?;
    write_to(
        out,
        &annotated_view(table, &properties, options),
        format,
        name,
    )
}

/// The view of `table` that writes `properties` (as [`annotated`] gives them), headed for
/// the desktop tool of `options`' flavour.
fn annotated_view<'a>(
    table: &'a PointTable,
    properties: &'a [Cow<'a, Property>],
    options: &AnnotateOptions,
) -> crate::table::TableView<'a> {
    let mut view = table.view();
    view.properties = properties.iter().map(Cow::as_ref).collect();
    view.csv_comment_header = options.flavour == Flavour::CloudCompare;
    view
}

/// The properties of an annotated output of `table` in `format`: the input's without a
/// previous run's results, then the new results; `path` names the output in errors.
fn annotated<'a>(
    path: &Path,
    format: Format,
    table: &'a PointTable,
    classes: &[Class],
    probabilities: &[[f32; 3]],
    options: &AnnotateOptions,
    choices: Choices,
) -> Result<Vec<Cow<'a, Property>>, DataError> {
    if classes.len() != table.len() || probabilities.len() != table.len() {
        return Err(DataError::InvalidOutput {
            path: path.to_path_buf(),
            what: format!(
                "{} classes and {} probabilities for {} points",
                classes.len(),
                probabilities.len(),
                table.len()
            ),
        });
    }
    let previous = Previous::of(&table.properties, choices);
    let mut properties: Vec<Cow<'_, Property>> = Vec::with_capacity(table.properties.len() + 8);
    for (k, p) in table.properties.iter().enumerate() {
        if previous.restore == Some(k) {
            properties.push(Cow::Owned(Property::new(CLASSIFICATION, p.values.clone())));
        } else if !previous.ours.contains(&k) {
            properties.push(Cow::Borrowed(p));
        }
    }
    add_annotation(
        &mut properties,
        format,
        classes,
        probabilities,
        options,
        choices,
    );
    Ok(properties)
}

/// Drops the results of a previous run from `table` (see the module documentation), so
/// that their memory is free while the cloud is labelled; the annotated output is the same.
pub fn drop_annotated(table: &mut PointTable) {
    let previous = Previous::of(&table.properties, Choices::of(table));
    if let Some(at) = previous.restore {
        table.properties[at].name = CLASSIFICATION.into();
    }
    let mut k = 0;
    table.properties.retain(|_| {
        k += 1;
        !previous.ours.contains(&(k - 1))
    });
}

/// The columns of a previous run's results found in a table.
#[derive(Debug, Default)]
struct Previous {
    /// The positions of the columns that run added.
    ours: Vec<usize>,
    /// The position of `input_classification`, which becomes `classification` again.
    restore: Option<usize>,
}

/// What an annotated output decides from every point of its input, not from each chunk
/// alone: whether the input's Classification is meaningful, whether its colours and
/// `quality` are a previous run's. A whole table's are [`Choices::of`] it; a file written in
/// chunks ([`write_annotated_chunks`]) takes every chunk's, [merged](Choices::merge).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Choices {
    /// The Classification the output keeps holds a code other than 0 and 1 (see
    /// [`ClassTarget::Auto`]) at some point.
    classified: bool,
    /// The colours are class colours at every point.
    class_coloured: bool,
    /// `quality` repeats `p_sharp` at every point.
    quality_repeats: bool,
}

impl Choices {
    /// The choices for the points of `table`.
    pub fn of(table: &PointTable) -> Self {
        let properties = &table.properties;
        let find = |name: &str| properties.iter().position(|p| p.name == name);
        let quality_repeats = match (find(QUALITY), Previous::names(properties)) {
            (Some(q), Some(names)) => {
                find(names[2]).is_some_and(|p| properties[q].values == properties[p].values)
            }
            _ => false,
        };
        let class_coloured = match RGB.map(find) {
            [Some(r), Some(g), Some(b)] if Previous::names(properties).is_some() => {
                let [r, g, b] = [r, g, b].map(|at| &properties[at].values);
                class_coloured(r, g, b)
            }
            _ => false,
        };
        let mut choices = Choices {
            classified: false,
            class_coloured,
            quality_repeats,
        };
        // The Classification the output keeps: a previous run's input one, if restored.
        let previous = Previous::of(properties, choices);
        let kept = match previous.restore {
            Some(at) => Some(at),
            None => find(CLASSIFICATION).filter(|at| !previous.ours.contains(at)),
        };
        choices.classified = kept.is_some_and(|at| has_classes(&properties[at].values));
        choices
    }

    /// The choices for the points of two chunks.
    pub fn merge(self, other: Self) -> Self {
        Choices {
            classified: self.classified || other.classified,
            class_coloured: self.class_coloured && other.class_coloured,
            quality_repeats: self.quality_repeats && other.quality_repeats,
        }
    }
}

impl Previous {
    /// The names of a previous run's results among `properties`, if there are any.
    fn names(properties: &[Property]) -> Option<&'static [&'static str; 4]> {
        let find = |name: &str| properties.iter().position(|p| p.name == name);
        NAMES
            .iter()
            .find(|names| names[1..].iter().all(|n| find(n).is_some()))
    }

    fn of(properties: &[Property], choices: Choices) -> Self {
        let find = |name: &str| properties.iter().position(|p| p.name == name);
        if Self::names(properties).is_none() {
            return Previous::default();
        }
        let mut ours: Vec<usize> = (NAMES.iter().flatten().chain(&CLASS_RGB))
            .filter_map(|n| find(n))
            .collect();
        ours.extend(find(QUALITY).filter(|_| choices.quality_repeats));
        if choices.class_coloured {
            ours.extend(RGB.map(find).into_iter().flatten());
        }
        let has_class = NAMES.iter().any(|names| find(names[0]).is_some());
        let restore = if has_class {
            None
        } else {
            ours.extend(find(CLASSIFICATION));
            find(INPUT_CLASSIFICATION)
        };
        Previous { ours, restore }
    }
}

/// True when every point's colour is a class colour, in 8 or (as LAS stores them) 16 bits.
fn class_coloured(r: &Column, g: &Column, b: &Column) -> bool {
    let eight = Class::ALL.map(|c| class_colour(c).map(f64::from));
    let sixteen = eight.map(|c| c.map(|v| v * 257.0));
    (0..r.len()).into_par_iter().all(|i| {
        let c = [r, g, b].map(|c| c.get_f64(i));
        eight.contains(&c) || sixteen.contains(&c)
    })
}

/// Adds the results to `properties` as `options` say for `format`: an input property of a
/// name they take (under any flavour) is kept as `input_<name>`, or dropped where the
/// options replace it.
fn add_annotation<'a>(
    properties: &mut Vec<Cow<'a, Property>>,
    format: Format,
    classes: &[Class],
    probabilities: &[[f32; 3]],
    options: &AnnotateOptions,
    choices: Choices,
) {
    let find = |properties: &[Cow<'a, Property>], name: &str| {
        properties.iter().position(|p| p.name == name)
    };
    let mut added = Vec::with_capacity(8);
    let names = options.flavour.names(format);
    let class_codes = |codes: ClassCodes| -> Column {
        Column::U8(classes.par_iter().map(|&c| codes.of(c)).collect())
    };
    // PCL filters on float fields only.
    let class = || match format {
        Format::Pcd => Column::F32(classes.par_iter().map(|&c| f32::from(c as u8)).collect()),
        _ => Column::U8(classes.par_iter().map(|&c| c as u8).collect()),
    };
    match (format, options.class_to) {
        (Format::Las { .. }, target) => {
            let classified = choices.classified;
            match target {
                ClassTarget::Auto if classified => added.push(Property::new(names[0], class())),
                ClassTarget::Extra => added.push(Property::new(names[0], class())),
                ClassTarget::Auto | ClassTarget::Classification(_) => {
                    let codes = match target {
                        ClassTarget::Classification(codes) => codes,
                        _ => ClassCodes::default(),
                    };
                    if let Some(at) = find(properties, CLASSIFICATION) {
                        let input = properties.remove(at);
                        if classified {
                            let kept = Property::new(INPUT_CLASSIFICATION, input.values.clone());
                            properties.insert(at, Cow::Owned(kept));
                        }
                    }
                    added.push(Property::new(CLASSIFICATION, class_codes(codes)));
                }
            }
        }
        _ => added.push(Property::new(names[0], class())),
    }
    for (k, name) in names[1..].iter().enumerate() {
        let p = Column::F32(probabilities.par_iter().map(|p| p[k]).collect());
        added.push(Property::new(*name, p));
    }
    if options.flavour == Flavour::MeshLab && format == Format::Ply {
        let p_sharp = added[added.len() - 2].values.clone();
        added.push(Property::new(QUALITY, p_sharp));
    }
    let has_colours = RGB.iter().all(|n| find(properties, n).is_some());
    let colour_names = match options.colours {
        Colours::KeepInput if has_colours => None,
        Colours::KeepInput => Some(RGB),
        Colours::Replace => {
            properties.retain(|p| !RGB.contains(&p.name.as_str()));
            Some(RGB)
        }
        Colours::Add => Some(CLASS_RGB),
    };
    for (k, name) in colour_names.into_iter().flatten().enumerate() {
        let c = Column::U8(classes.par_iter().map(|&c| class_colour(c)[k]).collect());
        added.push(Property::new(name, c));
    }
    for new in &added {
        // CloudCompare shows `scalar_class` as `class`: an input `class` beside it is kept
        // aside under either flavour's names.
        let alias = (NAMES.iter())
            .find_map(|row| row.iter().position(|n| *n == new.name))
            .map(|j| NAMES.map(|row| row[j]));
        let taken = |name: &str| name == new.name || alias.is_some_and(|a| a.contains(&name));
        if let Some(at) = properties.iter().position(|p| taken(&p.name)) {
            let input = &properties[at];
            let kept = Property::new(format!("input_{}", input.name), input.values.clone());
            properties[at] = Cow::Owned(kept);
        }
    }
    properties.extend(added.into_iter().map(Cow::Owned));
}

/// True when a LAS Classification holds a code other than 0 ("never classified") and 1
/// ("unclassified").
fn has_classes(classification: &Column) -> bool {
    (0..classification.len())
        .into_par_iter()
        .any(|i| classification.get_f64(i) > 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::read;
    use crate::xyz::Separator;
    use bounded_geom::PointCloud;

    const CLASSES: [Class; 3] = [Class::Sharp, Class::NonEdge, Class::Boundary];
    const PROBABILITIES: [[f32; 3]; 3] = [[0.1, 0.8, 0.1], [0.9, 0.05, 0.05], [0.2, 0.2, 0.6]];
    const EXTENSIONS: [&str; 8] = ["ply", "pcd", "xyz", "txt", "csv", "las", "laz", "e57"];

    /// Three points with an intensity and a LAS Classification of ground and building.
    fn sample() -> PointTable {
        let cloud =
            PointCloud::from_f64(&[[0.5, -1.25, 2.0], [1.5, 3.0, -4.0], [0.0, 0.0, 0.0]]).unwrap();
        let mut t = PointTable::new(cloud);
        t.set_property(Property::new("intensity", Column::U16(vec![1, 65535, 7])));
        t.set_property(Property::new("classification", Column::U8(vec![2, 6, 2])));
        t
    }

    fn names(t: &PointTable) -> Vec<&str> {
        t.properties.iter().map(|p| p.name.as_str()).collect()
    }

    fn values(t: &PointTable, name: &str) -> Vec<f64> {
        let column = t
            .property(name)
            .unwrap_or_else(|| panic!("no {name} in {:?}", names(t)));
        (0..t.len()).map(|i| column.get_f64(i)).collect()
    }

    #[test]
    fn a_second_run_replaces_the_first_runs_results_in_every_format() {
        let dir = tempfile::tempdir().unwrap();
        let codes = ClassTarget::Classification(ClassCodes::default());
        let options = [
            AnnotateOptions::default(),
            AnnotateOptions {
                class_to: codes,
                colours: Colours::Replace,
                flavour: Flavour::Plain,
            },
            AnnotateOptions {
                class_to: ClassTarget::Extra,
                colours: Colours::Add,
                flavour: Flavour::MeshLab,
            },
        ];
        for (k, options) in options.iter().enumerate() {
            for ext in EXTENSIONS {
                let write = |input: &PointTable, name: &str| {
                    let path = dir.path().join(format!("{name}{k}.{ext}"));
                    write_annotated_with(&path, input, &CLASSES, &PROBABILITIES, options).unwrap();
                    read(&path).unwrap()
                };
                let first = write(&sample(), "first");
                let second = write(&first, "second");
                assert_eq!(second, first, "{ext} {options:?}");
                let mut unique = names(&second);
                unique.sort();
                unique.dedup();
                assert_eq!(
                    unique.len(),
                    second.properties.len(),
                    "{:?}",
                    names(&second)
                );
                // Dropping the previous results first gives the same output.
                let mut dropped = first.clone();
                drop_annotated(&mut dropped);
                assert!(dropped.properties.len() < first.properties.len(), "{ext}");
                assert_eq!(write(&dropped, "third"), first, "{ext} {options:?}");
            }
        }
    }

    #[test]
    fn a_las_classification_replaced_by_codes_comes_back_on_a_second_run() {
        let dir = tempfile::tempdir().unwrap();
        let options = AnnotateOptions {
            class_to: ClassTarget::Classification(ClassCodes::default()),
            ..AnnotateOptions::default()
        };
        let path = dir.path().join("once.las");
        write_annotated_with(&path, &sample(), &CLASSES, &PROBABILITIES, &options).unwrap();
        let once = read(&path).unwrap();
        assert_eq!(values(&once, "classification"), [64.0, 1.0, 65.0]);
        assert_eq!(values(&once, "input_classification"), [2.0, 6.0, 2.0]);
        let mut restored = once.clone();
        drop_annotated(&mut restored);
        assert_eq!(values(&restored, "classification"), [2.0, 6.0, 2.0]);
        let left: Vec<&str> = names(&once)
            .into_iter()
            .filter(|n| !names(&restored).contains(n))
            .collect();
        assert_eq!(
            left,
            [
                "red",
                "green",
                "blue",
                "input_classification",
                "p_nonedge",
                "p_sharp",
                "p_boundary"
            ]
        );
    }

    fn annotate(table: &PointTable, ext: &str, options: &AnnotateOptions) -> PointTable {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(format!("out.{ext}"));
        write_annotated_with(&path, table, &CLASSES, &PROBABILITIES, options).unwrap();
        read(&path).unwrap()
    }

    #[test]
    fn input_colours_stay_unless_asked_and_class_colours_fill_colourless_clouds() {
        let mut coloured = sample();
        for (name, v) in RGB.iter().zip([[1u8, 2, 3], [4, 5, 6], [7, 8, 9]]) {
            coloured.set_property(Property::new(*name, Column::U8(v.to_vec())));
        }
        let with = |colours| AnnotateOptions {
            colours,
            ..AnnotateOptions::default()
        };
        let keep = annotate(&coloured, "ply", &with(Colours::KeepInput));
        assert_eq!(values(&keep, "red"), [1.0, 2.0, 3.0]);
        assert!(keep.property("class_red").is_none());
        let plain = annotate(&sample(), "ply", &with(Colours::KeepInput));
        assert_eq!(values(&plain, "red"), [255.0, 160.0, 0.0]);
        let replace = annotate(&coloured, "ply", &with(Colours::Replace));
        assert_eq!(values(&replace, "green"), [0.0, 160.0, 255.0]);
        assert!(replace.property("input_red").is_none());
        let add = annotate(&coloured, "pcd", &with(Colours::Add));
        assert_eq!(values(&add, "blue"), [7.0, 8.0, 9.0]);
        assert_eq!(values(&add, "class_red"), [255.0, 160.0, 0.0]);
    }

    #[test]
    fn las_classes_of_the_input_stay_where_they_are() {
        let codes = ClassCodes {
            non_edge: 0,
            sharp: 20,
            boundary: 21,
        };
        let with = |class_to| AnnotateOptions {
            class_to,
            ..AnnotateOptions::default()
        };
        // Ground and building: the class goes to an Extra Bytes field.
        let auto = annotate(&sample(), "las", &with(ClassTarget::Auto));
        assert_eq!(values(&auto, "classification"), [2.0, 6.0, 2.0]);
        assert_eq!(values(&auto, "class"), [1.0, 0.0, 2.0]);
        // Only "unclassified": nothing to keep, the codes go to Classification.
        let mut unclassified = sample();
        unclassified.set_property(Property::new(CLASSIFICATION, Column::U8(vec![1, 0, 1])));
        let auto = annotate(&unclassified, "laz", &with(ClassTarget::Auto));
        assert_eq!(values(&auto, "classification"), [64.0, 1.0, 65.0]);
        assert!(auto.property("class").is_none() && auto.property(INPUT_CLASSIFICATION).is_none());
        let chosen = annotate(&sample(), "las", &with(ClassTarget::Classification(codes)));
        assert_eq!(values(&chosen, "classification"), [20.0, 0.0, 21.0]);
        assert_eq!(values(&chosen, INPUT_CLASSIFICATION), [2.0, 6.0, 2.0]);
        let extra = annotate(&unclassified, "las", &with(ClassTarget::Extra));
        assert_eq!(values(&extra, "classification"), [1.0, 0.0, 1.0]);
        assert_eq!(values(&extra, "class"), [1.0, 0.0, 2.0]);
    }

    #[test]
    fn options_parse_from_their_command_line_names() {
        let codes = |non_edge, sharp, boundary| ClassCodes {
            non_edge,
            sharp,
            boundary,
        };
        assert_eq!("auto".parse(), Ok(ClassTarget::Auto));
        assert_eq!("extra".parse(), Ok(ClassTarget::Extra));
        assert_eq!(
            "classification".parse(),
            Ok(ClassTarget::Classification(codes(1, 64, 65)))
        );
        assert_eq!(
            "classification:0, 6,255".parse(),
            Ok(ClassTarget::Classification(codes(0, 6, 255)))
        );
        for bad in [
            "classification:1,2",
            "classification:1,2,256",
            "class",
            "auto:1",
        ] {
            assert!(bad.parse::<ClassTarget>().is_err(), "{bad}");
        }
        assert_eq!("keep".parse(), Ok(Colours::KeepInput));
        assert_eq!("replace".parse(), Ok(Colours::Replace));
        assert_eq!("add".parse(), Ok(Colours::Add));
        assert!("Keep".parse::<Colours>().is_err());
        assert_eq!("cloudcompare".parse(), Ok(Flavour::CloudCompare));
        assert_eq!("plain".parse(), Ok(Flavour::Plain));
        assert_eq!("meshlab".parse(), Ok(Flavour::MeshLab));
        assert!("open3d".parse::<Flavour>().unwrap_err().contains("meshlab"));
    }

    #[test]
    fn csv_headers_are_comments_for_cloudcompare_only() {
        let header = |format, flavour| {
            let options = AnnotateOptions {
                flavour,
                ..AnnotateOptions::default()
            };
            let mut out = Vec::new();
            let name = Path::new("out");
            write_annotated_to(
                &mut out,
                format,
                name,
                &sample(),
                &CLASSES,
                &PROBABILITIES,
                &options,
            )
            .unwrap();
            let text = String::from_utf8(out).unwrap();
            text.lines().next().unwrap().to_string()
        };
        let (csv, space) = (Format::Xyz(Separator::Comma), Format::Xyz(Separator::Space));
        assert!(header(csv, Flavour::CloudCompare).starts_with("//x,y,z,intensity,"));
        assert!(header(csv, Flavour::Plain).starts_with("x,y,z,intensity,"));
        assert!(header(csv, Flavour::MeshLab).starts_with("x,y,z,"));
        assert!(header(space, Flavour::Plain).starts_with("//x y z intensity "));
        // Read back, the `//` header names the columns.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.csv");
        write_annotated_with(
            &path,
            &sample(),
            &CLASSES,
            &PROBABILITIES,
            &Default::default(),
        )
        .unwrap();
        assert_eq!(
            values(&read(&path).unwrap(), "scalar_class"),
            [1.0, 0.0, 2.0]
        );
    }

    #[test]
    fn names_follow_the_flavour_and_a_foreign_class_is_kept_aside() {
        let mut t = sample();
        t.set_property(Property::new("class", Column::U8(vec![9, 9, 9])));
        let names_in = |ext: &str, flavour| {
            let options = AnnotateOptions {
                flavour,
                ..AnnotateOptions::default()
            };
            let back = annotate(&t, ext, &options);
            assert_eq!(values(&back, "input_class"), [9.0; 3], "{ext}");
            names(&back)
                .into_iter()
                .map(String::from)
                .collect::<Vec<_>>()
        };
        let cc = names_in("csv", Flavour::CloudCompare);
        assert!(
            cc.ends_with(
                &[
                    "input_class",
                    "scalar_class",
                    "scalar_p_nonedge",
                    "scalar_p_sharp",
                    "scalar_p_boundary",
                    "red",
                    "green",
                    "blue"
                ]
                .map(String::from)
            ),
            "{cc:?}"
        );
        let pcd = names_in("pcd", Flavour::CloudCompare);
        assert!(pcd.contains(&"p_sharp".to_string()) && !pcd.contains(&"scalar_class".to_string()));
        let meshlab = names_in("ply", Flavour::MeshLab);
        assert!(meshlab.contains(&"quality".to_string()) && meshlab.contains(&"class".to_string()));
        let back = annotate(
            &t,
            "ply",
            &AnnotateOptions {
                flavour: Flavour::MeshLab,
                ..Default::default()
            },
        );
        assert_eq!(back.property("quality"), back.property("p_sharp"));
        let pcd = annotate(&t, "pcd", &AnnotateOptions::default());
        assert_eq!(
            pcd.property("class").unwrap().scalar_type(),
            crate::table::ScalarType::F32
        );
    }
}
