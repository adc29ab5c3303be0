//! ABC dataset loader: an OBJ mesh plus its features YAML give a labelled cloud.
//!
//! The paper's recipe: the cloud is the mesh's vertices; vertices on curves flagged
//! `sharp: true` in the features file are sharp edges, vertices on open mesh borders (edges
//! used by exactly one face) are boundary, everything else is non-edge. Sharp wins where a
//! sharp curve runs along a border.
//!
//! Only the needed subsets of both formats are read: OBJ `v` and `f` lines (faces in the
//! `i`, `i/t`, `i//n` and `i/t/n` forms, 1-based or negative indices; other lines are
//! skipped), and from the YAML the `curves:` list with each curve's `sharp:` flag and
//! `vert_indices:` (0-based, block `- 1` or flow `[1, 2]` lists).
//!
//! A directory of models ([`load_dir`], `bounded train --data abc:DIR`) pairs every OBJ file
//! in it or below it with the features file beside it: the OBJ's name with its last
//! `trimesh` replaced by `features` (the ABC naming: `00000006_trimesh_000.obj`,
//! `00000006_features_000.yml`) or unchanged, ending in `.yml` or `.yaml`.
//!
//! ```no_run
//! let cloud = bounded_data::abc::load(
//!     "abc/00000006_trimesh_000.obj".as_ref(),
//!     "abc/00000006_features_000.yml".as_ref(),
//! )?;
//! println!("{:?}", cloud.class_counts());
//! # Ok::<(), bounded_data::DataError>(())
//! ```

use crate::{DataError, LabelledCloud};
use bounded_geom::{Class, PointCloud};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

/// Loads an ABC model: `obj_path` (the mesh) and `yaml_path` (its features file).
pub fn load(obj_path: &Path, yaml_path: &Path) -> Result<LabelledCloud, DataError> {
    let mesh = read_obj(obj_path)?;
    let curves = read_curves(yaml_path)?;
    let mut labels = vec![Class::NonEdge; mesh.vertices.len()];
    for v in border_vertices(&mesh.faces) {
        labels[v as usize] = Class::Boundary;
    }
    for curve in curves.iter().filter(|c| c.sharp) {
        for &(index, line) in &curve.vertices {
            let label = labels.get_mut(index).ok_or_else(|| {
                malformed(
                    yaml_path,
                    format!(
                        "line {line}: vertex index {index} out of range (the mesh has {} vertices)",
                        mesh.vertices.len()
                    ),
                )
            })?;
            *label = Class::Sharp;
        }
    }
    let cloud = PointCloud::from_f64(&mesh.vertices).map_err(|source| DataError::Geom {
        path: obj_path.to_path_buf(),
        source,
    })?;
    Ok(LabelledCloud { cloud, labels })
}

/// Loads every ABC model in `dir` and its subdirectories (see the module docs for how a mesh
/// finds its features file), in path order, each named by its OBJ file's stem.
pub fn load_dir(dir: &Path) -> Result<Vec<(String, LabelledCloud)>, DataError> {
    let mut meshes = Vec::new();
    find_meshes(dir, &mut meshes)?;
    if meshes.is_empty() {
        return Err(DataError::Dataset {
            path: dir.to_path_buf(),
            what: "no ABC meshes (.obj files) found".into(),
        });
    }
    meshes.sort();
    (meshes.iter())
        .map(|obj| Ok((crate::dataset::stem(obj), load(obj, &features_file(obj)?)?)))
        .collect()
}

/// Adds the `.obj` files in `dir` and below it (symbolic links not followed) to `meshes`.
fn find_meshes(dir: &Path, meshes: &mut Vec<PathBuf>) -> Result<(), DataError> {
    let io = |source| DataError::io(dir, source);
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let entry = entry.map_err(io)?;
        let path = entry.path();
        if entry.file_type().map_err(io)?.is_dir() {
            find_meshes(&path, meshes)?;
        } else if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
        {
            meshes.push(path);
        }
    }
    Ok(())
}

/// The features file beside the mesh `obj`.
fn features_file(obj: &Path) -> Result<PathBuf, DataError> {
    let stem = obj.file_stem().unwrap_or_default().to_string_lossy();
    let renamed = match stem.rfind("trimesh") {
        Some(i) => format!("{}features{}", &stem[..i], &stem[i + "trimesh".len()..]),
        None => stem.to_string(),
    };
    let candidates =
        [&renamed, &stem.to_string()].map(|s| [format!("{s}.yml"), format!("{s}.yaml")]);
    (candidates.iter().flatten())
        .map(|name| obj.with_file_name(name))
        .find(|path| path.is_file())
        .ok_or_else(|| {
            malformed(
                obj,
                format!("no features file beside it (expected {renamed}.yml or {renamed}.yaml)"),
            )
        })
}

fn malformed(path: &Path, what: impl Into<String>) -> DataError {
    DataError::Malformed {
        path: path.to_path_buf(),
        what: what.into(),
    }
}

fn lines(path: &Path) -> Result<impl Iterator<Item = Result<String, DataError>>, DataError> {
    let io = |source| DataError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    Ok(BufReader::new(file).lines().map(move |l| l.map_err(io)))
}

/// The vertices and faces (0-based vertex indices) of an OBJ file.
struct ObjMesh {
    vertices: Vec<[f64; 3]>,
    faces: Vec<Vec<u32>>,
}

fn read_obj(path: &Path) -> Result<ObjMesh, DataError> {
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for (n, line) in lines(path)?.enumerate() {
        let line = line?;
        let number = n + 1;
        let bad = |what: String| malformed(path, format!("line {number}: {what}"));
        let mut tokens = line.split_whitespace();
        match tokens.next() {
            Some("v") => {
                let mut p = [0.0; 3];
                for c in &mut p {
                    let token = tokens
                        .next()
                        .ok_or_else(|| bad("a vertex needs three coordinates".into()))?;
                    *c = token
                        .parse::<f64>()
                        .ok()
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| {
                            bad(format!("bad coordinate {}", crate::error::quoted(token)))
                        })?;
                }
                vertices.push(p);
            }
            Some("f") => {
                let face = tokens
                    .map(|t| face_index(t, vertices.len()).map_err(&bad))
                    .collect::<Result<Vec<u32>, _>>()?;
                if face.len() < 3 {
                    return Err(bad(format!("a face needs 3 vertices, got {}", face.len())));
                }
                faces.push((number, face));
            }
            _ => {}
        }
    }
    // Positive indices may in principle point forward, so check them once all are read.
    for (number, face) in &faces {
        if let Some(&i) = face.iter().find(|&&i| i as usize >= vertices.len()) {
            return Err(malformed(
                path,
                format!(
                    "line {number}: face vertex {} out of range (the file has {} vertices)",
                    i + 1,
                    vertices.len()
                ),
            ));
        }
    }
    Ok(ObjMesh {
        vertices,
        faces: faces.into_iter().map(|(_, f)| f).collect(),
    })
}

/// The 0-based vertex of a face token `i`, `i/t`, `i//n` or `i/t/n`; a negative `i` counts
/// back from the `seen` vertices read so far.
fn face_index(token: &str, seen: usize) -> Result<u32, String> {
    let first = token.split('/').next().unwrap_or(token);
    let i: i64 = first
        .parse()
        .map_err(|_| format!("bad face vertex {}", crate::error::quoted(token)))?;
    let index = match i {
        0 => return Err("face vertex index 0 (OBJ indices start at 1)".into()),
        i if i > 0 => i - 1,
        i => seen as i64 + i,
    };
    u32::try_from(index)
        .map_err(|_| format!("face vertex {i} out of range ({seen} vertices before it)"))
}

/// Vertices on edges used by exactly one face.
fn border_vertices(faces: &[Vec<u32>]) -> Vec<u32> {
    let mut edges: Vec<(u32, u32)> = faces
        .iter()
        .flat_map(|f| {
            (0..f.len()).map(move |i| {
                let (a, b) = (f[i], f[(i + 1) % f.len()]);
                (a.min(b), a.max(b))
            })
        })
        .collect();
    edges.sort_unstable();
    edges
        .chunk_by(|x, y| x == y)
        .filter(|group| group.len() == 1)
        .flat_map(|group| [group[0].0, group[0].1])
        .collect()
}

/// One feature curve: its sharp flag and vertex indices (with their YAML line numbers).
#[derive(Debug, Default)]
struct Curve {
    sharp: bool,
    vertices: Vec<(usize, usize)>,
}

/// A line of YAML without its comment: indentation, text, line number.
struct YamlLine {
    indent: usize,
    text: String,
    number: usize,
}

/// Reads the `curves:` list of an ABC features file.
fn read_curves(path: &Path) -> Result<Vec<Curve>, DataError> {
    let mut yaml = Vec::new();
    for (n, line) in lines(path)?.enumerate() {
        let line = line?;
        let content = match line.find(" #") {
            Some(i) => &line[..i],
            None => &line,
        };
        let text = content.trim_start();
        if text.is_empty() || text.starts_with('#') || text.starts_with("---") {
            continue;
        }
        yaml.push(YamlLine {
            indent: content.len() - text.len(),
            text: text.trim_end().to_string(),
            number: n + 1,
        });
    }
    CurveParser { path, lines: &yaml }.parse()
}

struct CurveParser<'a> {
    path: &'a Path,
    lines: &'a [YamlLine],
}

impl CurveParser<'_> {
    fn error(&self, number: usize, what: impl std::fmt::Display) -> DataError {
        malformed(self.path, format!("line {number}: {what}"))
    }

    fn parse(&self) -> Result<Vec<Curve>, DataError> {
        let start = self
            .lines
            .iter()
            .position(|l| l.indent == 0 && key_value(&l.text).is_some_and(|(k, _)| k == "curves"))
            .ok_or_else(|| malformed(self.path, "no top-level `curves:` list"))?;
        let head = &self.lines[start];
        let (_, inline) = key_value(&head.text).unwrap_or(("", ""));
        if !inline.is_empty() {
            return if inline == "[]" {
                Ok(Vec::new())
            } else {
                Err(self.error(
                    head.number,
                    "expected a block list of curves after `curves:`",
                ))
            };
        }
        let body = &self.lines[start + 1..];
        let Some(first) = body.first().filter(|l| l.text.starts_with('-')) else {
            return Ok(Vec::new());
        };
        let item_indent = first.indent;
        let mut curves: Vec<(Curve, bool, bool, usize)> = Vec::new();
        let mut current_key = String::new();
        for line in body {
            let is_item = line.indent == item_indent && line.text.starts_with('-');
            if line.indent < item_indent || (line.indent == item_indent && !is_item) {
                break; // the next top-level key: the list is over
            }
            let mut text = line.text.as_str();
            if is_item {
                curves.push((Curve::default(), false, false, line.number));
                text = text[1..].trim_start();
                if text.is_empty() {
                    continue;
                }
            }
            let Some((curve, has_sharp, has_indices, _)) = curves.last_mut() else {
                return Err(self.error(line.number, "expected a curve item `- ...`"));
            };
            if let Some(value) = text.strip_prefix('-').filter(|_| !is_item) {
                // A block-list element of the current key.
                if current_key == "vert_indices" {
                    curve
                        .vertices
                        .push((self.index(value.trim(), line.number)?, line.number));
                }
                continue;
            }
            let Some((key, value)) = key_value(text) else {
                continue; // nested content of a key we do not read
            };
            current_key = key.to_string();
            match key {
                "sharp" => {
                    *has_sharp = true;
                    curve.sharp = match value.to_ascii_lowercase().as_str() {
                        "true" => true,
                        "false" => false,
                        other => {
                            return Err(self.error(
                                line.number,
                                format!(
                                    "`sharp` must be true or false, got {}",
                                    crate::error::quoted(other)
                                ),
                            ));
                        }
                    };
                }
                "vert_indices" => {
                    *has_indices = true;
                    if !value.is_empty() {
                        let list = value
                            .strip_prefix('[')
                            .and_then(|v| v.strip_suffix(']'))
                            .ok_or_else(|| {
                                self.error(
                                    line.number,
                                    format!(
                                        "expected a list `[...]`, got {}",
                                        crate::error::quoted(value)
                                    ),
                                )
                            })?;
                        for token in list.split(',').map(str::trim).filter(|t| !t.is_empty()) {
                            curve
                                .vertices
                                .push((self.index(token, line.number)?, line.number));
                        }
                    }
                }
                _ => {}
            }
        }
        curves
            .into_iter()
            .map(
                |(curve, has_sharp, has_indices, number)| match (has_sharp, has_indices) {
                    (true, true) => Ok(curve),
                    (false, _) => Err(self.error(number, "curve without a `sharp:` flag")),
                    (_, false) => Err(self.error(number, "curve without `vert_indices:`")),
                },
            )
            .collect()
    }

    fn index(&self, token: &str, number: usize) -> Result<usize, DataError> {
        token.parse().map_err(|_| {
            self.error(
                number,
                format!("bad vertex index {}", crate::error::quoted(token)),
            )
        })
    }
}

/// Splits `key: value` (value possibly empty); `None` when the text is not a mapping entry.
fn key_value(text: &str) -> Option<(&str, &str)> {
    let (key, value) = text.split_once(':')?;
    let key = key.trim();
    (!key.is_empty() && !key.contains(' ')).then_some((key, value.trim()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An open box (no top) whose bottom is a fan around a centre vertex (index 8).
    const OPEN_BOX: &str = "\
# open box
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vt 0 0
vn 0 0 1
v 0.5 0.5 0
f 1/1/1 2/1/1 -1/1/1
f 2//1 3//1 9//1
f 3/1 4/1 9/1
f 4 1 9
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
";

    fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> std::path::PathBuf {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    fn load_str(obj: &str, yaml: &str) -> Result<LabelledCloud, DataError> {
        let dir = tempfile::tempdir().unwrap();
        load(&write(&dir, "m.obj", obj), &write(&dir, "m.yml", yaml))
    }

    #[test]
    fn labels_sharp_curves_then_borders() {
        let yaml = "\
curves:
- sharp: true
  type: Line
  vert_indices:
  - 0
  - 1
  - 2
  - 3 # a comment
  vert_parameters:
  - 0.0
  - 7.0
- type: Line
  sharp: false
  vert_indices: [4, 5, 8]
- sharp: True
  vert_indices: [7]
surfaces:
- type: Plane
  vert_indices:
  - 8
";
        let c = load_str(OPEN_BOX, yaml).unwrap();
        use Class::{Boundary as B, NonEdge as N, Sharp as S};
        // Bottom ring sharp; top ring boundary (open rim) except vertex 7, on a sharp curve;
        // the non-sharp curve and the surface list change nothing.
        assert_eq!(c.labels, vec![S, S, S, S, B, B, B, S, N]);
        assert_eq!(c.cloud.position_f64(8), [0.5, 0.5, 0.0]);
    }

    #[test]
    fn nested_curve_items_and_empty_lists() {
        let yaml = "curves:\n  -\n    sharp: true\n    vert_indices: []\n";
        let c = load_str(OPEN_BOX, yaml).unwrap();
        assert_eq!(c.class_counts(), [5, 0, 4]);
        let c = load_str(OPEN_BOX, "surfaces: []\ncurves: []\n").unwrap();
        assert_eq!(c.class_counts(), [5, 0, 4]);
    }

    fn error_of(obj: &str, yaml: &str) -> String {
        load_str(obj, yaml).unwrap_err().to_string()
    }

    #[test]
    fn malformed_inputs_name_the_line_and_the_problem() {
        let ok_yaml = "curves:\n- sharp: true\n  vert_indices: [0]\n";
        let cases = [
            (
                OPEN_BOX.replace("f 4 1 9", "f 4 x 9"),
                ok_yaml,
                "line 16: bad face vertex 'x'",
            ),
            (
                OPEN_BOX.replace("f 4 1 9", "f 4 0 9"),
                ok_yaml,
                "line 16: face vertex index 0",
            ),
            (
                OPEN_BOX.replace("f 4 1 9", "f 4 1 19"),
                ok_yaml,
                "line 16: face vertex 19 out of range",
            ),
            (
                OPEN_BOX.replace("f 4 1 9", "f 4 1"),
                ok_yaml,
                "line 16: a face needs 3 vertices",
            ),
            (
                OPEN_BOX.replace("v 1 1 1", "v 1 nan 1"),
                ok_yaml,
                "line 8: bad coordinate 'nan'",
            ),
            (
                OPEN_BOX.replace("v 1 1 1", "v 1 1"),
                ok_yaml,
                "line 8: a vertex needs three",
            ),
            (
                OPEN_BOX.into(),
                "curve:\n- sharp: true\n",
                "no top-level `curves:` list",
            ),
            (
                OPEN_BOX.into(),
                "curves:\n- sharp: maybe\n  vert_indices: [0]\n",
                "line 2: `sharp` must be",
            ),
            (
                OPEN_BOX.into(),
                "curves:\n- sharp: true\n  vert_indices: [0, a]\n",
                "line 3: bad vertex index 'a'",
            ),
            (
                OPEN_BOX.into(),
                "curves:\n- sharp: true\n  vert_indices:\n  - 9\n",
                "line 4: vertex index 9 out of range",
            ),
            (
                OPEN_BOX.into(),
                "curves:\n- sharp: true\n",
                "line 2: curve without `vert_indices:`",
            ),
            (
                OPEN_BOX.into(),
                "curves:\n- vert_indices: [1]\n",
                "line 2: curve without a `sharp:` flag",
            ),
            (
                OPEN_BOX.into(),
                "curves:\n- sharp: true\n  vert_indices: 3\n",
                "line 3: expected a list",
            ),
        ];
        for (obj, yaml, expect) in cases {
            let e = error_of(&obj, yaml);
            assert!(e.contains(expect), "{e:?} should contain {expect:?}");
        }
    }

    #[test]
    fn missing_file_is_an_io_error_naming_it() {
        let e = load(
            Path::new("/nonexistent/m.obj"),
            Path::new("/nonexistent/m.yml"),
        )
        .unwrap_err();
        assert!(matches!(e, DataError::Io { .. }));
        assert!(e.to_string().starts_with("/nonexistent/m.obj"), "{e}");
    }

    #[test]
    fn a_directory_pairs_each_mesh_with_its_features_file() {
        let dir = tempfile::tempdir().unwrap();
        let sharp = "curves:\n- sharp: true\n  vert_indices: [0]\n";
        write(&dir, "00000002_trimesh_001.obj", OPEN_BOX);
        write(&dir, "00000002_features_001.yml", sharp);
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        write(&dir, "sub/plain.OBJ", OPEN_BOX);
        write(&dir, "sub/plain.yaml", "curves: []\n");
        write(&dir, "notes.txt", "not a mesh");
        let models = load_dir(dir.path()).unwrap();
        let names: Vec<&str> = models.iter().map(|m| m.0.as_str()).collect();
        assert_eq!(names, ["00000002_trimesh_001", "plain"]);
        assert_eq!(models[0].1.class_counts(), [4, 1, 4]);
        assert_eq!(models[1].1.class_counts(), [5, 0, 4]);

        write(&dir, "lone.obj", OPEN_BOX);
        let e = load_dir(dir.path()).unwrap_err().to_string();
        assert!(
            e.contains("lone.obj: no features file beside it (expected lone.yml"),
            "{e}"
        );
        let empty = tempfile::tempdir().unwrap();
        let e = load_dir(empty.path()).unwrap_err().to_string();
        assert!(e.contains("no ABC meshes"), "{e}");
    }
}
