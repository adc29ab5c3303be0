use bounded_geom::{Class, PointCloud};

/// A point cloud with one ground-truth [`Class`] per point.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelledCloud {
    /// The positions.
    pub cloud: PointCloud,
    /// One label per point, same order as `cloud`.
    pub labels: Vec<Class>,
}

impl LabelledCloud {
    /// Number of points of each class, indexed by `Class as usize`.
    pub fn class_counts(&self) -> [usize; 3] {
        Class::counts(&self.labels)
    }
}
