//! Convex polyhedra cut from a box by random planes: corners and creases of arbitrary angles.

use super::mesh::Mesh;
use super::sample::random_direction;
use bounded_geom::vec3::{V3, add, cross, dot, normalize, scale, sub};
use rand::Rng;

/// Cut planes stay at least this far (degrees) from every face's orientation, so each new
/// crease deviates from flat by at least as much.
const MIN_CUT_ANGLE_DEG: f64 = 25.0;

/// A convex polyhedron as outward-facing convex polygons.
pub(crate) struct Polyhedron {
    faces: Vec<Vec<V3>>,
}

impl Polyhedron {
    /// The box `[-a/2, a/2] x [-b/2, b/2] x [-c/2, c/2]`.
    pub(crate) fn cuboid(size: V3) -> Self {
        let h = scale(size, 0.5);
        let corner = |i: usize| [0, 1, 2].map(|a| if i >> a & 1 == 1 { h[a] } else { -h[a] });
        // Corner indices per face, counter-clockwise seen from outside.
        let faces = [
            [0, 2, 6, 4],
            [1, 5, 7, 3],
            [0, 4, 5, 1],
            [2, 3, 7, 6],
            [0, 1, 3, 2],
            [4, 6, 7, 5],
        ];
        Self {
            faces: faces
                .iter()
                .map(|f| f.iter().map(|&i| corner(i)).collect())
                .collect(),
        }
    }

    fn normal(face: &[V3]) -> V3 {
        let n = face.len();
        normalize((0..n).fold([0.0; 3], |acc, i| {
            add(acc, cross(face[i], face[(i + 1) % n]))
        }))
    }

    fn vertices(&self) -> impl Iterator<Item = V3> + '_ {
        self.faces.iter().flatten().copied()
    }

    /// Cuts off a random slice: a plane with a random normal (kept away from every face
    /// orientation) at 50..90% of the extent along it. Gives up after a few tries.
    pub(crate) fn cut_randomly(&mut self, rng: &mut impl Rng) {
        let count = self.vertices().count().max(1) as f64;
        let centre = scale(self.vertices().fold([0.0; 3], add), 1.0 / count);
        let min_cos = MIN_CUT_ANGLE_DEG.to_radians().cos();
        for _ in 0..20 {
            let n = normalize(random_direction(rng));
            let clear = self
                .faces
                .iter()
                .all(|f| dot(Self::normal(f), n).abs() < min_cos);
            if !clear {
                continue;
            }
            let reach = self
                .vertices()
                .map(|v| dot(sub(v, centre), n))
                .fold(0.0, f64::max);
            let point = add(centre, scale(n, reach * rng.random_range(0.5..0.9)));
            self.cut(point, n);
            return;
        }
    }

    /// Keeps the part with `<p - point, normal> <= 0` and closes it with the cut face.
    fn cut(&mut self, point: V3, normal: V3) {
        let side = |p: V3| dot(sub(p, point), normal);
        let mut section = Vec::new();
        let mut faces = Vec::with_capacity(self.faces.len() + 1);
        for face in &self.faces {
            let mut kept = Vec::with_capacity(face.len() + 2);
            for i in 0..face.len() {
                let (a, b) = (face[i], face[(i + 1) % face.len()]);
                let (da, db) = (side(a), side(b));
                if da <= 0.0 {
                    kept.push(a);
                }
                if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
                    // Computed from the ordered pair so both faces of an edge get the
                    // same point.
                    let (u, v, du, dv) = if a < b {
                        (a, b, da, db)
                    } else {
                        (b, a, db, da)
                    };
                    let x = add(u, scale(sub(v, u), du / (du - dv)));
                    kept.push(x);
                    section.push(x);
                }
            }
            if kept.len() >= 3 {
                faces.push(kept);
            }
        }
        if section.len() >= 3 {
            // Order the section around its centroid, counter-clockwise seen along `normal`.
            let c = scale(
                section.iter().copied().fold([0.0; 3], add),
                1.0 / section.len() as f64,
            );
            let u = normalize(sub(section[0], c));
            let v = cross(normal, u);
            section.sort_by(|&p, &q| {
                let angle = |x: V3| dot(sub(x, c), v).atan2(dot(sub(x, c), u));
                angle(p).total_cmp(&angle(q))
            });
            section.dedup();
            faces.push(section);
        }
        self.faces = faces;
    }

    /// The faces as triangle fans (unwelded).
    pub(crate) fn to_mesh(&self) -> Mesh {
        let mut m = Mesh::default();
        for face in &self.faces {
            let ring = m.vertices_of(face.iter().copied());
            for w in ring[1..].windows(2) {
                m.triangles.push([ring[0], w[0], w[1]]);
            }
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn corner_cut_of_a_cube_adds_a_triangle_and_three_creases() {
        let mut p = Polyhedron::cuboid([1.0; 3]);
        let n = normalize([1.0, 1.0, 1.0]);
        // Cuts the (+,+,+) corner through the points at distance 0.25 from it on its edges.
        p.cut([0.5, 0.5, 0.25], n);
        assert_eq!(p.faces.len(), 7);
        assert_eq!(p.faces.last().map(Vec::len), Some(3));
        let m = p.to_mesh().welded();
        assert_eq!(m.vertices.len(), 10);
        let f = m.features();
        assert!(f.border.is_empty());
        let length: f64 = f
            .sharp
            .iter()
            .map(super::super::mesh::Polyline::length)
            .sum();
        // 12 cube edges, three shortened by 0.25, plus the triangle of side 0.25 sqrt 2.
        let expect = 12.0 - 0.75 + 3.0 * 0.25 * std::f64::consts::SQRT_2;
        assert!((length - expect).abs() < 1e-9, "{length} vs {expect}");
    }

    #[test]
    fn random_cuts_keep_the_surface_closed() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..20 {
            let mut p = Polyhedron::cuboid([1.0, 0.7, 0.4]);
            for _ in 0..4 {
                p.cut_randomly(&mut rng);
            }
            let f = p.to_mesh().welded().features();
            assert!(f.border.is_empty());
            assert!(f.sharp.len() >= 12);
        }
    }
}
