//! Writes a generated airborne-like survey as a grid of LAS tiles, and all of it as one LAS
//! file (the tiles' points in tile order: the survey as one cloud), for measuring
//! `bounded detect` tile by tile against one cloud.
//!
//! `cargo run --release --example synthetic_survey -- DIR POINTS GRID` writes
//! `DIR/tile_J_I.las` (GRID x GRID tiles) and `DIR/merged.las`. The scene: rolling ground
//! with a building every 50 m (flat roofs, walls), about 10 points per square metre.

use std::path::{Path, PathBuf};

use bounded_data::format;
use bounded_data::table::{PointTable, PositionType};
use bounded_geom::{PointCloud, uniform_stream};

/// The building of the 50 m block at `(bx, by)`: its footprint corners and height.
fn building(bx: i64, by: i64) -> ([f64; 2], [f64; 2], f64) {
    let mut r = uniform_stream((bx as u64).wrapping_mul(7919) ^ (by as u64).wrapping_mul(104_729));
    let (w, d, h) = (10.0 + 15.0 * r(), 10.0 + 15.0 * r(), 5.0 + 10.0 * r());
    let (x0, y0) = (
        bx as f64 * 50.0 + 5.0 + (35.0 - w) * r(),
        by as f64 * 50.0 + 5.0 + (35.0 - d) * r(),
    );
    ([x0, y0], [x0 + w, y0 + d], h)
}

fn ground(x: f64, y: f64) -> f64 {
    5.0 * (x / 100.0).sin() * (y / 130.0).cos()
}

/// `n` points of the scene over the square of side `side` at the origin.
fn scene(n: usize, side: f64, seed: u64) -> Vec<[f64; 3]> {
    let mut r = uniform_stream(seed);
    let mut points = Vec::with_capacity(n);
    while points.len() < n {
        let (x, y) = (side * r(), side * r());
        let (lo, hi, h) = building((x / 50.0).floor() as i64, (y / 50.0).floor() as i64);
        let z0 = ground(lo[0], lo[1]);
        let inside = (lo[0]..hi[0]).contains(&x) && (lo[1]..hi[1]).contains(&y);
        points.push(if inside {
            [x, y, z0 + h]
        } else {
            [x, y, ground(x, y)]
        });
        // A wall point for about one ground point in ten, on the nearest building's walls.
        if r() < 0.1 && points.len() < n {
            let t = r() * 2.0 * ((hi[0] - lo[0]) + (hi[1] - lo[1]));
            let (w, d) = (hi[0] - lo[0], hi[1] - lo[1]);
            let (wx, wy) = if t < w {
                (lo[0] + t, lo[1])
            } else if t < w + d {
                (hi[0], lo[1] + t - w)
            } else if t < 2.0 * w + d {
                (hi[0] - (t - w - d), hi[1])
            } else {
                (lo[0], hi[1] - (t - 2.0 * w - d))
            };
            points.push([wx, wy, z0 + h * r()]);
        }
    }
    points
}

/// Writes `points` on the centimetre grid (scale 0.01, offset 0), the same in every file, so
/// a point of a tile has exactly its position in the merged file.
fn write(path: &Path, points: &[[f64; 3]]) -> Result<(), Box<dyn std::error::Error>> {
    let mut table = PointTable::new(PointCloud::from_f64(points)?);
    table.position_type = PositionType::Scaled {
        scale: [0.01; 3],
        offset: [0.0; 3],
    };
    format::write(path, &table)?;
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [dir, n, grid] = args.as_slice() else {
        return Err("usage: synthetic_survey DIR POINTS GRID".into());
    };
    let (dir, n, grid) = (
        PathBuf::from(dir),
        n.parse::<usize>()?,
        grid.parse::<usize>()?,
    );
    std::fs::create_dir_all(&dir)?;
    let side = (n as f64 / 10.0).sqrt();
    // On the centimetre grid already: every file then stores the same integers for a point.
    let points: Vec<[f64; 3]> = (scene(n, side, 1).into_iter())
        .map(|p| p.map(|c| (c * 100.0).round() / 100.0))
        .collect();
    let cell = |c: f64| ((c / side * grid as f64) as usize).min(grid - 1);
    let mut tiles = vec![Vec::new(); grid * grid];
    for p in &points {
        tiles[cell(p[1]) * grid + cell(p[0])].push(*p);
    }
    drop(points);
    let mut merged = Vec::with_capacity(n);
    for (t, tile) in tiles.iter().enumerate() {
        write(
            &dir.join(format!("tile_{}_{}.las", t / grid, t % grid)),
            tile,
        )?;
        merged.extend_from_slice(tile);
    }
    write(&dir.join("merged.las"), &merged)?;
    println!(
        "{} points over {side:.0} m x {side:.0} m in {} tiles",
        merged.len(),
        tiles.len()
    );
    Ok(())
}
