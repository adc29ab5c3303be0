use crate::GeomError;

/// A point cloud of positions only.
///
/// Points are stored as `f32` offsets from an `f64` origin: 12 bytes per point. The
/// constructors from `f64` positions take the centre of the bounding box, which keeps
/// about a 16-millionth of the cloud's extent for any real-world coordinates; a reader
/// of `f32` coordinates takes the origin 0 and keeps them exactly. Two clouds are equal
/// when every point has the same absolute position, whatever their origins.
#[derive(Debug, Clone)]
pub struct PointCloud {
    origin: [f64; 3],
    points: Vec<[f32; 3]>,
}

impl PointCloud {
    /// Builds a cloud from absolute `f64` positions, re-centred on their bounding-box centre.
    ///
    /// Fails on an empty slice or on any NaN / infinite coordinate.
    pub fn from_f64(positions: &[[f64; 3]]) -> Result<Self, GeomError> {
        Self::from_iter_f64(positions.len(), |i| positions[i])
    }

    /// Builds a cloud from `len` absolute positions produced by `position(i)`.
    ///
    /// Lets readers hand over positions without building an intermediate `Vec`.
    pub fn from_iter_f64(
        len: usize,
        position: impl Fn(usize) -> [f64; 3],
    ) -> Result<Self, GeomError> {
        if len == 0 {
            return Err(GeomError::Empty);
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for i in 0..len {
            let p = position(i);
            if !p.iter().all(|c| c.is_finite()) {
                return Err(GeomError::NonFinite { index: i, value: p });
            }
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let origin = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]));
        let points = (0..len)
            .map(|i| {
                let p = position(i);
                [0, 1, 2].map(|a| (p[a] - origin[a]) as f32)
            })
            .collect();
        Ok(Self { origin, points })
    }

    /// Builds a cloud from positions already relative to `origin`.
    ///
    /// Fails on an empty slice or on any NaN / infinite coordinate.
    pub fn from_local(origin: [f64; 3], points: Vec<[f32; 3]>) -> Result<Self, GeomError> {
        if points.is_empty() {
            return Err(GeomError::Empty);
        }
        if let Some((index, p)) = points
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
        {
            return Err(GeomError::NonFinite {
                index,
                value: p.map(f64::from),
            });
        }
        Ok(Self { origin, points })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the cloud holds no points (never, for a constructed cloud).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The origin that [`points`](Self::points) are relative to.
    pub fn origin(&self) -> [f64; 3] {
        self.origin
    }

    /// Re-centred positions, relative to [`origin`](Self::origin).
    pub fn points(&self) -> &[[f32; 3]] {
        &self.points
    }

    /// Absolute position of point `i`.
    pub fn position_f64(&self, i: usize) -> [f64; 3] {
        let p = self.points[i];
        [0, 1, 2].map(|a| self.origin[a] + f64::from(p[a]))
    }
}

impl PartialEq for PointCloud {
    fn eq(&self, other: &Self) -> bool {
        self.len() == other.len()
            && (0..self.len()).all(|i| self.position_f64(i) == other.position_f64(i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recentres_utm_coordinates_with_millimetre_precision() {
        let c =
            PointCloud::from_f64(&[[5_403_150.0, 0.0, 0.0], [5_403_150.001, 0.0, 0.0]]).unwrap();
        let d = c.points()[1][0] - c.points()[0][0];
        assert!((d - 0.001).abs() < 1e-6, "{d}");
        assert!((c.position_f64(1)[0] - 5_403_150.001).abs() < 1e-6);
    }

    #[test]
    fn rejects_empty_and_non_finite() {
        assert_eq!(PointCloud::from_f64(&[]), Err(GeomError::Empty));
        let e = PointCloud::from_f64(&[[0.0; 3], [f64::NAN, 0.0, 0.0]]).unwrap_err();
        assert!(matches!(e, GeomError::NonFinite { index: 1, .. }));
    }

    #[test]
    fn equal_means_the_same_absolute_positions() {
        let centred = PointCloud::from_f64(&[[0.5, 1.0, 2.0], [1.5, 3.0, 4.0]]).unwrap();
        let at_zero = PointCloud::from_local([0.0; 3], vec![[0.5, 1.0, 2.0], [1.5, 3.0, 4.0]]);
        assert_ne!(centred.origin(), at_zero.as_ref().unwrap().origin());
        assert_eq!(Ok(centred.clone()), at_zero);
        let moved = PointCloud::from_local([0.0; 3], vec![[0.5, 1.0, 2.0], [1.5, 3.0, 4.5]]);
        assert_ne!(Ok(centred.clone()), moved);
        let shorter = PointCloud::from_local([0.0; 3], vec![[0.5, 1.0, 2.0]]);
        assert_ne!(Ok(centred), shorter);
    }
}
