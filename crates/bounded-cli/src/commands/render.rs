//! `bounded render`: a shaded picture of a cloud coloured by class.

use super::sources;
use crate::canvas::{Canvas, Rgb};
use crate::cli::{ColourBy, RenderArgs};
use crate::pipeline;
use crate::render::{View, render};
use anyhow::{Context, Result, bail};
use bounded_data::format;
use bounded_data::labels::{self, Convention};
use bounded_geom::{Class, PointCloud};

/// The picture of `cloud` with one class per point.
pub fn picture(cloud: &PointCloud, classes: &[Class], view: View, size: [usize; 2]) -> Canvas {
    let colours: Vec<Rgb> = classes.iter().map(|&c| format::class_colour(c)).collect();
    render(cloud.points(), &colours, view, size[0], size[1])
}

pub fn run(args: &RenderArgs) -> Result<()> {
    let [width, height] = args.size[..] else {
        bail!("--size takes width,height");
    };
    if !(16..=16384).contains(&width) || !(16..=16384).contains(&height) {
        bail!("--size {width},{height}: each side must be 16..16384 pixels");
    }
    let view = match args.view.as_deref() {
        Some(&[azimuth, elevation]) => View { azimuth, elevation },
        _ => View::default(),
    };
    let table = format::read(&args.input)?;
    let classes = match args.by {
        ColourBy::Class => {
            if labels::class_column(&table).is_none() {
                bail!(
                    "{}: no 'class' property to colour by; --by detect runs detection first, \
                     --by truth reads PCEDNet or Bazazian label colours",
                    args.input.display()
                );
            }
            labels::from_table(table.clone(), Convention::ClassProperty, &args.input)?.labels
        }
        ColourBy::Truth => sources::labelled(&args.input, Class::NonEdge)?.labels,
        ColourBy::Detect => {
            let detector = pipeline::detector(Default::default())?;
            pipeline::detect(&detector, &table.cloud, true)
                .with_context(|| args.input.display().to_string())?
                .classes
        }
    };
    picture(&table.cloud, &classes, view, [width, height]).save_png(&args.output)?;
    eprintln!("{} points; wrote {}", table.len(), args.output.display());
    Ok(())
}
