//! Rotation matrices from quaternions: the poses of scans and of generated shapes.

/// The row-major rotation matrix of the quaternion `[w, x, y, z]`, normalised first (the
/// zero quaternion gives the identity).
pub fn rotation_of_quaternion(q: [f64; 4]) -> [[f64; 3]; 3] {
    let n = q
        .iter()
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt()
        .max(f64::MIN_POSITIVE);
    let [w, x, y, z] = q.map(|v| v / n);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(m: &[[f64; 3]; 3], p: [f64; 3]) -> [f64; 3] {
        m.map(|row| row[0] * p[0] + row[1] * p[1] + row[2] * p[2])
    }

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < 1e-12)
    }

    #[test]
    fn quarter_turns_and_scaled_quaternions() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        // A quarter turn about z takes x to y and y to -x.
        let about_z = rotation_of_quaternion([h, 0.0, 0.0, h]);
        assert!(close(apply(&about_z, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]));
        assert!(close(apply(&about_z, [0.0, 1.0, 0.0]), [-1.0, 0.0, 0.0]));
        assert!(close(apply(&about_z, [0.0, 0.0, 1.0]), [0.0, 0.0, 1.0]));
        // About x: y to z. A quaternion's length does not matter.
        let about_x = rotation_of_quaternion([3.0, 3.0, 0.0, 0.0]);
        assert!(close(apply(&about_x, [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]));
        let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(rotation_of_quaternion([0.0; 4]), identity);
        assert_eq!(rotation_of_quaternion([2.0, 0.0, 0.0, 0.0]), identity);
    }

    #[test]
    fn any_quaternion_gives_an_orthonormal_matrix() {
        for q in [
            [0.3, -1.2, 0.7, 2.0],
            [-5.0, 0.1, 0.1, 0.1],
            [1e-3, 2e-3, -1e-3, 4e-3],
        ] {
            let m = rotation_of_quaternion(q);
            for i in 0..3 {
                for j in 0..3 {
                    let dot: f64 = (0..3).map(|k| m[i][k] * m[j][k]).sum();
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((dot - want).abs() < 1e-12, "{q:?} {i} {j}: {dot}");
                }
            }
        }
    }
}
