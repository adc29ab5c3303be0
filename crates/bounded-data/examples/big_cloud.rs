//! Writes a large synthetic cloud for throughput and memory measurements of `bounded detect`:
//! N points uniformly on the surface of a unit cube (uniform random, so no crease rows),
//! streamed straight into the output file.
//!
//! `cargo run --release -p bounded-data --example big_cloud -- 10000000 /tmp/cube10m.ply`

use bounded_data::format;
use bounded_data::table::PointTable;
use bounded_geom::PointCloud;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().ok_or("usage: big_cloud N OUTPUT")?.parse()?;
    let output = args.next().ok_or("usage: big_cloud N OUTPUT")?;
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let points: Vec<[f32; 3]> = (0..n)
        .map(|_| {
            let face = rng.random_range(0..6usize);
            let (u, v) = (rng.random::<f32>(), rng.random::<f32>());
            let side = (face % 2) as f32;
            match face / 2 {
                0 => [side, u, v],
                1 => [u, side, v],
                _ => [u, v, side],
            }
        })
        .collect();
    let cloud = PointCloud::from_local([0.0; 3], points)?;
    format::write(output.as_ref(), &PointTable::new(cloud))?;
    Ok(())
}
