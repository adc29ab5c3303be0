//! The project's one 3-vector type: `[f64; 3]` and the small functions on it.
//!
//! Plain arrays rather than nalgebra's `Vector3`: positions cross every API as `[f64; 3]`
//! (`PointCloud::position_f64`, the formats, the generator's meshes), so a vector library would
//! add a conversion at each boundary and a dependency for a dozen one-line functions. The SIMD
//! kernels of the features keep their own lane layouts.

/// A point or direction in 3D.
pub type V3 = [f64; 3];

/// `a + b`.
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a - b`.
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a s`.
pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Dot product.
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product.
pub fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Euclidean length.
pub fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

/// `a / |a|`, or zero for a zero vector (callers treat zero as "no direction").
pub fn normalize(a: V3) -> V3 {
    let n = norm(a);
    if n > 0.0 { scale(a, 1.0 / n) } else { [0.0; 3] }
}

/// `a + t (b - a)`.
pub fn lerp(a: V3, b: V3, t: f64) -> V3 {
    add(a, scale(sub(b, a), t))
}

/// Where on the segment `a`-`b` (0 at `a`, 1 at `b`) the point nearest `p` lies.
pub fn segment_parameter(p: V3, a: V3, b: V3) -> f64 {
    let ab = sub(b, a);
    let len2 = dot(ab, ab);
    if len2 > 0.0 {
        (dot(sub(p, a), ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Distance from `p` to the segment `a`-`b`.
pub fn segment_distance(p: V3, a: V3, b: V3) -> f64 {
    norm(sub(p, lerp(a, b, segment_parameter(p, a, b))))
}

/// Two unit vectors completing the unit vector `n` to a right-handed orthonormal frame
/// (`e1 x e2 = n`).
pub fn tangent_frame(n: V3) -> (V3, V3) {
    let helper = if n[0].abs() < 0.6 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = normalize(cross(helper, n));
    (e1, cross(n, e1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_distance_inside_and_beyond_the_ends() {
        let (a, b) = ([0.0, 0.0, 0.0], [2.0, 0.0, 0.0]);
        assert_eq!(segment_distance([1.0, 3.0, 0.0], a, b), 3.0);
        assert_eq!(segment_distance([5.0, 4.0, 0.0], a, b), 5.0);
        assert_eq!(cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
    }
}
