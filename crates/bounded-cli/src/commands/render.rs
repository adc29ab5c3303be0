//! `bounded render`: a shaded picture of a cloud coloured by class.

use crate::cli::{ColourBy, RenderArgs};
use crate::pipeline;
use anyhow::{Context, Result, bail};
use bounded_data::labels::{self, Convention};
use bounded_data::picture::{self, View, render_classes};
use bounded_data::{dataset, format};
use bounded_geom::Class;

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
    picture::check_png(&args.output)?;
    let table = format::read(&args.input)?;
    let classes = match args.by {
        ColourBy::Class => (labels::from_table(
            table.clone(),
            Convention::ClassProperty,
            &args.input,
        ))
        .context(
            "--by detect runs detection first, --by truth reads PCEDNet or Bazazian label colours",
        )?
        .labels,
        ColourBy::Truth => dataset::read_labelled(&args.input, Class::NonEdge)?.labels,
        ColourBy::Detect => {
            let detector = pipeline::detector(&Default::default())?;
            pipeline::detect(&detector, &table.cloud, true)
                .with_context(|| args.input.display().to_string())?
                .classes
        }
    };
    render_classes(&table.cloud, &classes, view, width, height).save_png(&args.output)?;
    eprintln!("{} points; wrote {}", table.len(), args.output.display());
    Ok(())
}
