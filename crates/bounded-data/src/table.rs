//! A point table: positions plus the extra per-point properties a file carried.
//!
//! Readers return a [`PointTable`] so that a detection run can write every input property
//! back out next to its results. Positions live in the [`PointCloud`] (f64 origin + f32
//! offsets); every other property is a typed [`Column`] stored column-wise, which is both
//! compact and what the binary codecs decode and encode in bulk.

use bounded_geom::PointCloud;
use std::fmt::Display;
use std::str::FromStr;

/// The scalar type of one property, as in PLY / PCD / LAS extra bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ScalarType {
    /// Unsigned 8-bit integer.
    U8,
    /// Signed 8-bit integer.
    I8,
    /// Unsigned 16-bit integer.
    U16,
    /// Signed 16-bit integer.
    I16,
    /// Unsigned 32-bit integer.
    U32,
    /// Signed 32-bit integer.
    I32,
    /// 32-bit float.
    F32,
    /// 64-bit float.
    F64,
}

impl ScalarType {
    /// Size of one value in bytes.
    pub fn size(self) -> usize {
        match self {
            ScalarType::U8 | ScalarType::I8 => 1,
            ScalarType::U16 | ScalarType::I16 => 2,
            ScalarType::U32 | ScalarType::I32 | ScalarType::F32 => 4,
            ScalarType::F64 => 8,
        }
    }

    /// True for the two float types.
    pub fn is_float(self) -> bool {
        matches!(self, ScalarType::F32 | ScalarType::F64)
    }

    /// Encodes `value` converted to this type (`as` semantics: saturating, truncating) into
    /// the first [`size`](Self::size) bytes of `out`.
    #[inline]
    pub(crate) fn encode_f64(self, value: f64, out: &mut [u8], endian: Endian) {
        match self {
            ScalarType::U8 => u8::from_f64(value).encode(out, endian),
            ScalarType::I8 => i8::from_f64(value).encode(out, endian),
            ScalarType::U16 => u16::from_f64(value).encode(out, endian),
            ScalarType::I16 => i16::from_f64(value).encode(out, endian),
            ScalarType::U32 => u32::from_f64(value).encode(out, endian),
            ScalarType::I32 => i32::from_f64(value).encode(out, endian),
            ScalarType::F32 => f32::from_f64(value).encode(out, endian),
            ScalarType::F64 => value.encode(out, endian),
        }
    }
}

/// How the positions were (or are to be) stored in a file.
///
/// Writers keep the input precision: a cloud read from `float` coordinates is written as
/// `float`, one read from `double` or LAS scaled integers as `double` (PLY, PCD, XYZ) or with
/// the same scale and offset (LAS).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PositionType {
    /// 32-bit float coordinates.
    F32,
    /// 64-bit float coordinates.
    F64,
    /// LAS-style integers: `coordinate = offset + scale * integer`.
    Scaled {
        /// Scale per axis.
        scale: [f64; 3],
        /// Offset per axis.
        offset: [f64; 3],
    },
}

impl PositionType {
    /// The type to use for a new cloud: `F32` unless an absolute coordinate is so large
    /// (beyond 100 km) that `f32` would lose centimetres, or the cloud's extent is extreme
    /// (offsets stored scaled, see [`PointCloud`]).
    pub fn for_cloud(cloud: &PointCloud) -> Self {
        let far = cloud
            .origin()
            .iter()
            .any(|o| o.abs() > 1e5 || !o.is_finite())
            || cloud.scale() != 1.0;
        if far {
            PositionType::F64
        } else {
            PositionType::F32
        }
    }

    /// The float type used by formats without scaled integers.
    pub fn float_type(self) -> ScalarType {
        match self {
            PositionType::F32 => ScalarType::F32,
            PositionType::F64 | PositionType::Scaled { .. } => ScalarType::F64,
        }
    }
}

/// Byte order of binary data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Endian {
    /// Least significant byte first.
    Little,
    /// Most significant byte first.
    Big,
}

/// One primitive property type: byte codecs, text parsing and the lossless `f64` view.
pub(crate) trait Scalar: Copy + Display + FromStr + Default + 'static {
    /// Size in bytes.
    const SIZE: usize;
    /// Decodes from exactly `SIZE` bytes.
    fn decode(bytes: &[u8], endian: Endian) -> Self;
    /// Encodes into exactly `SIZE` bytes.
    fn encode(self, out: &mut [u8], endian: Endian);
    /// The value as `f64` (exact for every supported type).
    fn to_f64(self) -> f64;
    /// `value` converted with Rust `as` semantics (saturating, truncating floats to integers).
    fn from_f64(value: f64) -> Self;
}

macro_rules! scalar {
    ($($t:ty),*) => {$(
        impl Scalar for $t {
            const SIZE: usize = std::mem::size_of::<$t>();
            fn decode(bytes: &[u8], endian: Endian) -> Self {
                let mut a = [0u8; std::mem::size_of::<$t>()];
                a.copy_from_slice(&bytes[..Self::SIZE]);
                match endian {
                    Endian::Little => <$t>::from_le_bytes(a),
                    Endian::Big => <$t>::from_be_bytes(a),
                }
            }
            fn encode(self, out: &mut [u8], endian: Endian) {
                let a = match endian {
                    Endian::Little => self.to_le_bytes(),
                    Endian::Big => self.to_be_bytes(),
                };
                out[..Self::SIZE].copy_from_slice(&a);
            }
            fn to_f64(self) -> f64 {
                self as f64
            }
            fn from_f64(value: f64) -> Self {
                value as $t
            }
        }
    )*};
}
scalar!(u8, i8, u16, i16, u32, i32, f32, f64);

/// The values of one property for all points.
#[derive(Debug, Clone, PartialEq)]
pub enum Column {
    /// Unsigned 8-bit values.
    U8(Vec<u8>),
    /// Signed 8-bit values.
    I8(Vec<i8>),
    /// Unsigned 16-bit values.
    U16(Vec<u16>),
    /// Signed 16-bit values.
    I16(Vec<i16>),
    /// Unsigned 32-bit values.
    U32(Vec<u32>),
    /// Signed 32-bit values.
    I32(Vec<i32>),
    /// 32-bit float values.
    F32(Vec<f32>),
    /// 64-bit float values.
    F64(Vec<f64>),
}

/// Runs `$body` with `$v` bound to the column's typed vector.
macro_rules! with_values {
    ($column:expr, $v:ident => $body:expr) => {
        match $column {
            Column::U8($v) => $body,
            Column::I8($v) => $body,
            Column::U16($v) => $body,
            Column::I16($v) => $body,
            Column::U32($v) => $body,
            Column::I32($v) => $body,
            Column::F32($v) => $body,
            Column::F64($v) => $body,
        }
    };
}

impl Column {
    /// An empty column of type `ty` with room for `capacity` values.
    pub fn with_capacity(ty: ScalarType, capacity: usize) -> Self {
        match ty {
            ScalarType::U8 => Column::U8(Vec::with_capacity(capacity)),
            ScalarType::I8 => Column::I8(Vec::with_capacity(capacity)),
            ScalarType::U16 => Column::U16(Vec::with_capacity(capacity)),
            ScalarType::I16 => Column::I16(Vec::with_capacity(capacity)),
            ScalarType::U32 => Column::U32(Vec::with_capacity(capacity)),
            ScalarType::I32 => Column::I32(Vec::with_capacity(capacity)),
            ScalarType::F32 => Column::F32(Vec::with_capacity(capacity)),
            ScalarType::F64 => Column::F64(Vec::with_capacity(capacity)),
        }
    }

    /// The type of the values.
    pub fn scalar_type(&self) -> ScalarType {
        match self {
            Column::U8(_) => ScalarType::U8,
            Column::I8(_) => ScalarType::I8,
            Column::U16(_) => ScalarType::U16,
            Column::I16(_) => ScalarType::I16,
            Column::U32(_) => ScalarType::U32,
            Column::I32(_) => ScalarType::I32,
            Column::F32(_) => ScalarType::F32,
            Column::F64(_) => ScalarType::F64,
        }
    }

    /// Number of values.
    pub fn len(&self) -> usize {
        with_values!(self, v => v.len())
    }

    /// True when the column holds no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Keeps the values `i` with `keep[i]` true, in order (`keep` has one flag per value).
    pub(crate) fn retain(&mut self, keep: &[bool]) {
        with_values!(self, v => retain_flagged(v, keep))
    }

    /// Value `i` as `f64` (exact for every type). Panics when `i` is out of range, like
    /// slice indexing.
    pub fn get_f64(&self, i: usize) -> f64 {
        with_values!(self, v => v[i].to_f64())
    }

    /// Appends `value` converted with Rust `as` semantics (NaN becomes 0 in integer columns).
    pub(crate) fn push_f64(&mut self, value: f64) {
        with_values!(self, v => v.push(Scalar::from_f64(value)))
    }

    /// Parses one text token and appends it; the error says why the token is not a value
    /// of this type.
    pub(crate) fn push_token(&mut self, token: &str) -> Result<(), String> {
        let ty = self.scalar_type();
        with_values!(self, v => push_parsed(v, token, ty))
    }

    /// Appends the values of one property from `records` records of `stride` bytes in
    /// `bytes`, the property starting at byte `offset` of each record.
    pub(crate) fn decode_strided(
        &mut self,
        bytes: &[u8],
        stride: usize,
        offset: usize,
        endian: Endian,
    ) {
        with_values!(self, v => decode_into(v, bytes, stride, offset, endian))
    }

    /// Appends `count` values from `bytes`, stored contiguously (PCD compressed layout).
    pub(crate) fn decode_packed(&mut self, bytes: &[u8], endian: Endian) {
        let size = self.scalar_type().size();
        self.decode_strided(bytes, size, 0, endian);
    }

    /// Writes values `first..first + n` into `n` records of `stride` bytes of `out`, at
    /// byte `offset` of each record.
    pub(crate) fn encode_strided(
        &self,
        first: usize,
        out: &mut [u8],
        stride: usize,
        offset: usize,
        endian: Endian,
    ) {
        with_values!(self, v => encode_from(v, first, out, stride, offset, endian))
    }

    /// Calls `f(k, value)` for the values `first + k`, `k < n`, as `f64`: one typed loop per
    /// column type rather than a type dispatch per value.
    pub(crate) fn for_each_f64(&self, first: usize, n: usize, mut f: impl FnMut(usize, f64)) {
        with_values!(self, v => {
            for (k, x) in v[first..first + n].iter().enumerate() {
                f(k, x.to_f64());
            }
        })
    }

    /// Writes value `i` as text (shortest representation that reads back exactly).
    pub(crate) fn write_text(
        &self,
        i: usize,
        out: &mut impl std::io::Write,
    ) -> std::io::Result<()> {
        with_values!(self, v => write!(out, "{}", v[i]))
    }
}

fn push_parsed<T: Scalar>(v: &mut Vec<T>, token: &str, ty: ScalarType) -> Result<(), String> {
    match token.parse::<T>() {
        Ok(x) => {
            v.push(x);
            Ok(())
        }
        // Integer properties written as "12.0" by some tools: accept exact integral floats.
        Err(_) => match token.parse::<f64>() {
            Ok(f) if !ty.is_float() && f.fract() == 0.0 && T::from_f64(f).to_f64() == f => {
                v.push(T::from_f64(f));
                Ok(())
            }
            _ => Err(format!(
                "{} is not a valid {ty:?} value",
                crate::error::quoted(token)
            )),
        },
    }
}

fn decode_into<T: Scalar>(
    v: &mut Vec<T>,
    bytes: &[u8],
    stride: usize,
    offset: usize,
    endian: Endian,
) {
    let records = bytes.len() / stride;
    v.reserve(records);
    v.extend(
        bytes
            .chunks_exact(stride)
            .map(|record| T::decode(&record[offset..offset + T::SIZE], endian)),
    );
}

fn encode_from<T: Scalar>(
    v: &[T],
    first: usize,
    out: &mut [u8],
    stride: usize,
    offset: usize,
    endian: Endian,
) {
    for (record, &x) in out.chunks_exact_mut(stride).zip(&v[first..]) {
        x.encode(&mut record[offset..offset + T::SIZE], endian);
    }
}

/// A named per-point property.
#[derive(Debug, Clone, PartialEq)]
pub struct Property {
    /// The name as in the file (`intensity`, `nx`, `red`, ...).
    pub name: String,
    /// One value per point.
    pub values: Column,
}

impl Property {
    /// A property named `name` with `values`.
    pub fn new(name: impl Into<String>, values: Column) -> Self {
        Self {
            name: name.into(),
            values,
        }
    }
}

/// Positions and every other per-point property of a cloud file.
#[derive(Debug, Clone, PartialEq)]
pub struct PointTable {
    /// The positions.
    pub cloud: PointCloud,
    /// How the positions were stored in the input, reused on output.
    pub position_type: PositionType,
    /// The other properties, in file order, each with one value per point.
    pub properties: Vec<Property>,
    /// The positions exactly as read, kept only when the cloud's `f32` offsets do not give
    /// them back (`f64` coordinates, or LAS integers finer than `f32` resolves): the
    /// writers use them, so an output never moves a point. `None` for new clouds.
    pub exact_positions: Option<ExactPositions>,
    /// The header records of a LAS input (CRS, other VLRs, Extra Bytes descriptors), which a
    /// LAS output carries over; `None` for other inputs.
    pub las_header: Option<crate::las::InputHeader>,
}

/// Input positions kept beside the cloud, in the input's own form: LAS integers take half
/// the memory of the doubles they stand for.
#[derive(Debug, Clone, PartialEq)]
pub enum ExactPositions {
    /// Coordinates as read.
    Float(Vec<[f64; 3]>),
    /// LAS scaled integers `steps`: the position is `scale * step + offset` per axis.
    Scaled {
        /// Size of one step per axis.
        scale: [f64; 3],
        /// Position of step 0 per axis.
        offset: [f64; 3],
        /// The integers as read.
        steps: Vec<[i32; 3]>,
    },
}

impl ExactPositions {
    /// Number of points.
    pub fn len(&self) -> usize {
        match self {
            Self::Float(p) => p.len(),
            Self::Scaled { steps, .. } => steps.len(),
        }
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Absolute position of point `i` (panics when out of range, like indexing).
    pub fn get(&self, i: usize) -> [f64; 3] {
        match self {
            Self::Float(p) => p[i],
            Self::Scaled {
                scale,
                offset,
                steps,
            } => std::array::from_fn(|a| scale[a] * f64::from(steps[i][a]) + offset[a]),
        }
    }

    /// Writes coordinate `axis` of the points `first..first + out.len()` into `out`: one
    /// branch per run instead of one per value, so the loops vectorise.
    pub(crate) fn axis(&self, axis: usize, first: usize, out: &mut [f64]) {
        let range = first..first + out.len();
        match self {
            Self::Float(p) => {
                for (o, p) in out.iter_mut().zip(&p[range]) {
                    *o = p[axis];
                }
            }
            Self::Scaled {
                scale,
                offset,
                steps,
            } => {
                let (scale, offset) = (scale[axis], offset[axis]);
                for (o, n) in out.iter_mut().zip(&steps[range]) {
                    *o = scale * f64::from(n[axis]) + offset;
                }
            }
        }
    }
}

impl PointTable {
    /// A table of positions only, with the position type chosen by
    /// [`PositionType::for_cloud`].
    pub fn new(cloud: PointCloud) -> Self {
        Self {
            position_type: PositionType::for_cloud(&cloud),
            cloud,
            properties: Vec::new(),
            exact_positions: None,
            las_header: None,
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.cloud.len()
    }

    /// True when the table has no points (never, for a table read from a file).
    pub fn is_empty(&self) -> bool {
        self.cloud.is_empty()
    }

    /// The property named `name`, if any.
    pub fn property(&self, name: &str) -> Option<&Column> {
        self.properties
            .iter()
            .find(|p| p.name == name)
            .map(|p| &p.values)
    }

    /// Adds `property`, replacing one of the same name (so names stay unique).
    ///
    /// Panics when its length differs from the number of points: a programming error.
    pub fn set_property(&mut self, property: Property) {
        assert_eq!(
            property.values.len(),
            self.len(),
            "property '{}' must have one value per point",
            property.name
        );
        match self.properties.iter_mut().find(|p| p.name == property.name) {
            Some(existing) => *existing = property,
            None => self.properties.push(property),
        }
    }

    /// A borrowed view of the whole table, for the writers.
    pub fn view(&self) -> TableView<'_> {
        TableView {
            cloud: &self.cloud,
            position_type: self.position_type,
            properties: self.properties.iter().collect(),
            exact_positions: self.exact_positions.as_ref(),
            las_header: self.las_header.as_ref(),
            csv_comment_header: false,
        }
    }
}

/// What a writer writes: positions and an ordered list of borrowed properties.
///
/// Lets [`write_annotated`](crate::format::write_annotated) add result columns to a table
/// without copying it.
#[derive(Debug, Clone)]
pub struct TableView<'a> {
    /// The positions.
    pub cloud: &'a PointCloud,
    /// How to store the positions.
    pub position_type: PositionType,
    /// The properties, each with one value per point, names unique.
    pub properties: Vec<&'a Property>,
    /// The input's exact positions, if the table keeps them (see [`PointTable`]).
    pub exact_positions: Option<&'a ExactPositions>,
    /// The LAS input's header records, for a LAS output (see [`PointTable`]).
    pub las_header: Option<&'a crate::las::InputHeader>,
    /// Whether a CSV output's header line starts with `//`, as CloudCompare's own exports
    /// do: its loader takes names from such a line only (without it, it guesses columns of
    /// values in [-1, 1] to be normals). Space-separated headers always start with `//`.
    pub csv_comment_header: bool,
}

impl TableView<'_> {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.cloud.len()
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.cloud.is_empty()
    }

    /// Checks, before `path` is written, that every property has one value per point and
    /// that names are unique and not `x`, `y`, `z`.
    pub(crate) fn check(&self, path: &std::path::Path) -> Result<(), crate::DataError> {
        let invalid = |what| {
            Err(crate::DataError::InvalidOutput {
                path: path.to_path_buf(),
                what,
            })
        };
        let mut seen = std::collections::HashSet::new();
        for p in &self.properties {
            if p.values.len() != self.len() {
                return invalid(format!(
                    "property {} has {} values for {} points",
                    crate::error::quoted(&p.name),
                    p.values.len(),
                    self.len()
                ));
            }
            if p.name.is_empty() || p.name.contains(|c: char| c.is_whitespace() || c == ',') {
                return invalid(format!(
                    "property name {} is empty or has a space or comma",
                    crate::error::quoted(&p.name)
                ));
            }
            if matches!(p.name.as_str(), "x" | "y" | "z") || !seen.insert(p.name.as_str()) {
                return invalid(format!(
                    "property name {} is used twice",
                    crate::error::quoted(&p.name)
                ));
            }
        }
        Ok(())
    }

    /// Absolute position of point `i`, as the writers store it: the exact input position if
    /// kept, else the cloud's, on the LAS grid for scaled coordinates (so `x = scale * n +
    /// offset` prints as read). For a table just read, the position exactly as in the file.
    pub fn position(&self, i: usize) -> [f64; 3] {
        if let Some(exact) = self.exact_positions {
            return exact.get(i);
        }
        let p = self.cloud.position_f64(i);
        match self.position_type {
            PositionType::Scaled { scale, offset } => std::array::from_fn(|a| {
                scale[a] * ((p[a] - offset[a]) / scale[a]).round() + offset[a]
            }),
            _ => p,
        }
    }
}

/// Keeps the entries `i` of `values` with `keep[i]` true, in order (`keep` has one flag per
/// entry): the one way columns, points and their labels are thinned together.
pub(crate) fn retain_flagged<T>(values: &mut Vec<T>, keep: &[bool]) {
    let mut flags = keep.iter();
    values.retain(|_| flags.next().copied().unwrap_or(false));
}

/// Where the coordinate property `axis` (`"x"`, `"y"` or `"z"`, in any case) is among
/// `properties`: the one rule both [`from_properties`] and [`drop_non_finite`] read by.
fn coordinate_at(properties: &[Property], axis: &str) -> Option<usize> {
    properties
        .iter()
        .position(|p| p.name.eq_ignore_ascii_case(axis))
}

/// Leaves out of every column the points whose `x`, `y` or `z` is NaN or infinite, and returns
/// how many that were (none when a coordinate column is missing: [`from_properties`] names it).
pub(crate) fn drop_non_finite(properties: &mut [Property]) -> usize {
    let column = |axis| coordinate_at(properties, axis).map(|at| &properties[at].values);
    let (Some(x), Some(y), Some(z)) = (column("x"), column("y"), column("z")) else {
        return 0;
    };
    let keep: Vec<bool> = (0..x.len())
        .map(|i| [x, y, z].iter().all(|c| c.get_f64(i).is_finite()))
        .collect();
    let dropped = keep.iter().filter(|&&k| !k).count();
    if dropped > 0 {
        for p in properties.iter_mut() {
            p.values.retain(&keep);
        }
    }
    dropped
}

/// Checks the `names` of the properties read from `path` besides the coordinates: each once,
/// none another coordinate (in any case, as readers find them), so that the table can be
/// written and read back.
pub(crate) fn check_names<'a>(
    names: impl IntoIterator<Item = &'a str>,
    path: &std::path::Path,
) -> Result<(), crate::DataError> {
    let mut seen = std::collections::HashSet::new();
    for name in names {
        let coordinate = ["x", "y", "z"].iter().any(|a| name.eq_ignore_ascii_case(a));
        if coordinate || !seen.insert(name) {
            return Err(crate::DataError::malformed(
                path,
                format!(
                    "the property name {} appears twice",
                    crate::error::quoted(name)
                ),
            ));
        }
    }
    Ok(())
}

/// Builds a table from a file's properties: the cloud from its `x`, `y`, `z` columns (any
/// type), the rest kept; the error names `path` and what is missing or invalid. `f32`
/// coordinates are kept as they are ([`PositionType::F32`]); others are re-centred, with
/// the exact positions kept where the cloud's `f32` offsets lose digits, as readers do.
pub fn from_properties(
    mut properties: Vec<Property>,
    path: &std::path::Path,
) -> Result<PointTable, crate::DataError> {
    let mut take = |axis| {
        let at = coordinate_at(&properties, axis).ok_or_else(|| {
            crate::DataError::malformed(path, "the points have no x, y and z properties")
        })?;
        Ok::<_, crate::DataError>(properties.remove(at).values)
    };
    let x = take("x")?;
    let y = take("y")?;
    let z = take("z")?;
    check_names(properties.iter().map(|p| p.name.as_str()), path)?;
    let geom = |source| crate::DataError::Geom {
        path: path.to_path_buf(),
        source,
    };
    // `f32` coordinates are kept as they are (origin 0), so they come back bit for bit;
    // features use differences between neighbours in `f64`, which need no centring.
    if let (Column::F32(x), Column::F32(y), Column::F32(z)) = (&x, &y, &z) {
        let points = (x.iter().zip(y).zip(z))
            .map(|((&x, &y), &z)| [x, y, z])
            .collect();
        return Ok(PointTable {
            cloud: PointCloud::from_local([0.0; 3], points).map_err(geom)?,
            position_type: PositionType::F32,
            properties,
            exact_positions: None,
            las_header: None,
        });
    }
    // A typed fast path for doubles: no per-value dispatch in the hot loops.
    let (cloud, exact_positions) = match (&x, &y, &z) {
        (Column::F64(x), Column::F64(y), Column::F64(z)) => {
            exact_cloud(x.len(), |i| [x[i], y[i], z[i]])
        }
        _ => exact_cloud(x.len(), |i| [x.get_f64(i), y.get_f64(i), z.get_f64(i)]),
    }
    .map_err(geom)?;
    Ok(PointTable {
        cloud,
        position_type: PositionType::F64,
        properties,
        exact_positions,
        las_header: None,
    })
}

/// A cloud and, where it cannot give them back, the exact positions it was made from.
pub(crate) type ExactCloud = (PointCloud, Option<ExactPositions>);

/// The cloud of the `len` positions `position(i)`, and all of them again when the cloud
/// does not give some back exactly: the copy costs memory only where the cloud's `f32`
/// offsets lose digits.
fn exact_cloud(
    len: usize,
    position: impl Fn(usize) -> [f64; 3] + Sync,
) -> Result<ExactCloud, bounded_geom::GeomError> {
    use rayon::prelude::*;
    let cloud = PointCloud::from_iter_f64(len, &position)?;
    let lossless = (0..len)
        .into_par_iter()
        .all(|i| cloud.position_f64(i) == position(i));
    let exact = (!lossless)
        .then(|| ExactPositions::Float((0..len).into_par_iter().map(&position).collect()));
    Ok((cloud, exact))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strided_codecs_round_trip_both_endians() {
        // Two records of 3 bytes: a u16 at offset 1.
        let bytes = [9, 0x01, 0x02, 9, 0xff, 0x00];
        let mut le = Column::with_capacity(ScalarType::U16, 2);
        le.decode_strided(&bytes, 3, 1, Endian::Little);
        assert_eq!(le, Column::U16(vec![0x0201, 0x00ff]));
        let mut be = Column::with_capacity(ScalarType::U16, 2);
        be.decode_strided(&bytes, 3, 1, Endian::Big);
        assert_eq!(be, Column::U16(vec![0x0102, 0xff00]));
        let mut out = [9u8; 6];
        be.encode_strided(0, &mut out, 3, 1, Endian::Big);
        assert_eq!(out, bytes);
    }

    #[test]
    fn tokens_parse_with_type_checks() {
        let mut c = Column::with_capacity(ScalarType::U8, 3);
        c.push_token("255").unwrap();
        c.push_token("12.0").unwrap();
        assert!(c.push_token("256").is_err());
        assert!(c.push_token("1.5").is_err());
        assert!(c.push_token("abc").is_err());
        assert_eq!(c, Column::U8(vec![255, 12]));
    }

    #[test]
    fn positions_split_from_columns_and_set_property_replaces() {
        let columns = vec![
            Property::new("x", Column::F64(vec![5_403_150.5, 5_403_151.5])),
            Property::new("intensity", Column::U16(vec![7, 8])),
            Property::new("y", Column::F32(vec![1.0, 2.0])),
            Property::new("z", Column::I32(vec![-3, 4])),
        ];
        let mut table = from_properties(columns, std::path::Path::new("t.ply")).unwrap();
        assert_eq!(table.position_type, PositionType::F64);
        assert_eq!(table.cloud.position_f64(1), [5_403_151.5, 2.0, 4.0]);
        table.set_property(Property::new("intensity", Column::U8(vec![1, 2])));
        assert_eq!(table.properties.len(), 1);
        assert_eq!(table.property("intensity"), Some(&Column::U8(vec![1, 2])));
    }
}
