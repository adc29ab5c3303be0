//! The per-point proof that a tile's halo sufficed: its labels are those of the survey as
//! one cloud.
//!
//! A point's result depends only on the points within its *reach* (see
//! `bounded_nn::Detector::detect_blocks_with_reach`): the distance of its `k0`-th neighbour
//! for a one-stage model; for a two-stage one, that plus the largest such distance among its
//! neighbours, since its second stage reads their first-stage results. When the ball of that
//! radius around a tile point lies in the tile's [`Region`], every point of the survey within
//! it is loaded; the neighbour search is exact and breaks ties by index in the survey's order
//! (see [`crate::halo`]), so the point's neighbours, and for two stages its neighbours'
//! neighbours, are those it has in the whole survey, and so are its features and
//! probabilities, bit for bit. A point whose ball leaves the region is *unproven*; the tile is
//! then labelled again with a larger halo.
//!
//! The reach is computed in the loaded cloud: a point proven by it has the same reach in the
//! survey; an unproven point's may differ, so the radius it asks for is a guess.

use crate::Plan;
use crate::halo::Region;

/// A reach grown by this factor must fit: the neighbour search compares `f32` squared
/// distances and the reach is rounded to `f32`, each a few units of 2^-24 off; 2^-16 covers
/// them with room to spare.
const MARGIN: f64 = 1.0 + 1.0 / 65536.0;

/// The proof over a tile's points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Verdict {
    /// Points whose reach leaves the region.
    pub unproven: usize,
    /// The smallest halo radius (absolute units) that holds every point's reach as computed
    /// (see [`Region::radius_for`]): what a run with that halo would need, if its reaches were
    /// the same.
    pub needed: f64,
}

/// Checks the tile points at offsets `points` (in the frame of `plan`) with `reach` each,
/// loaded with the halo of `region`.
pub fn check(plan: &Plan, region: &Region, points: &[[f32; 3]], reach: &[f32]) -> Verdict {
    let mut verdict = Verdict {
        unproven: 0,
        needed: 0.0,
    };
    for (&p, &r) in points.iter().zip(reach) {
        let r = f64::from(r) * MARGIN;
        if r > region.room(p) {
            verdict.unproven += 1;
        }
        verdict.needed = verdict.needed.max(region.radius_for(p, r));
    }
    verdict.needed *= plan.frame().scale;
    verdict
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Input;

    /// Two tiles side by side: x 0..10 and 10..20, y 0..10, z 0..1 (frame origin (10, 5, 0.5),
    /// scale 1: offsets are positions minus the origin).
    fn plan() -> Plan {
        let input = |name: &str, x: f64| Input {
            path: name.into(),
            lo: [x, 0.0, 0.0],
            hi: [x + 10.0, 10.0, 1.0],
            points: 1,
        };
        Plan::new(vec![input("a.las", 0.0), input("b.las", 10.0)]).unwrap()
    }

    #[test]
    fn a_reach_is_proven_when_it_fits_before_the_one_finite_side() {
        let plan = plan();
        assert_eq!(plan.frame().origin, [10.0, 5.0, 0.5]);
        // Tile a at radius 2: x ends at offset 2 (absolute 12); every other side lies on the
        // survey's bounds and is infinitely far.
        let region = Region::around(&plan, 0, 2.0);
        assert!(region.contains([2.0, 1e9, -1e9]) && !region.contains([2.5, 0.0, 0.0]));
        // A point at x = 9 (offset -1) has room 3 to the side at offset 2.
        let p = [-1.0, 4.0, 0.0];
        assert_eq!(region.room(p), 3.0);
        let verdict = check(&plan, &region, &[p, p], &[2.9, 3.0]);
        // 3 grown by the margin no longer fits; it would at a radius of that less the point's
        // distance 1 to the tile's side.
        assert_eq!(verdict.unproven, 1);
        assert_eq!(verdict.needed, 3.0 * MARGIN - 1.0);
        // A reach past the far end of tile b needs only the radius that takes the side
        // beyond the survey (10): then nothing lies past it.
        assert_eq!(region.radius_for(p, 50.0), 10.0);
        assert!(Region::around(&plan, 0, 10.0).is_everything());
        assert!(!Region::around(&plan, 0, 9.9).is_everything());
    }
}
