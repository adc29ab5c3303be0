//! Command-line arguments.

use bounded_data::annotate::{ClassTarget, Colours, Flavour};
use bounded_data::synth::NoiseDirection;
use bounded_nn::{Decision, EmbeddedModel};
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::num::NonZeroUsize;
use std::path::PathBuf;

/// Find sharp edges and boundaries in 3D point clouds, from positions alone.
#[derive(Debug, Parser)]
#[command(name = "bounded", version, about, long_about = None)]
pub struct Cli {
    /// Worker threads (default: all cores; at most 8 per core).
    #[arg(long, global = true, value_parser = threads)]
    pub threads: Option<usize>,
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Threads per core beyond which `--threads` is refused: more only add switching (1000
/// threads on 5,000 points took 10 s instead of a fraction of one).
const THREADS_PER_CORE: usize = 8;

/// Parses `--threads`: at least 1, at most [`THREADS_PER_CORE`] per core of this machine.
fn threads(arg: &str) -> Result<usize, String> {
    let n: usize = arg.parse().map_err(|e| format!("{e}"))?;
    let cores = std::thread::available_parallelism().map_or(1, NonZeroUsize::get);
    let most = THREADS_PER_CORE * cores;
    match n {
        0 => Err("at least 1 thread is needed".into()),
        n if n > most => Err(format!(
            "{n} threads on {cores} cores would only add switching; at most {most} \
             ({THREADS_PER_CORE} per core)"
        )),
        n => Ok(n),
    }
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Label every point of a cloud: non-edge, sharp edge or boundary.
    ///
    /// Example: bounded detect scan.las -o labelled.las
    Detect(DetectArgs),
    /// Train a classifier on labelled clouds or a generated set.
    ///
    /// Example: bounded train --data generated/ -o my.bmodel
    Train(TrainArgs),
    /// Score a model on labelled clouds (per model and medians).
    ///
    /// Example: bounded eval --data ../shared/datasets/pcednet/default --peers ../shared/datasets/pcednet/peers.csv
    Eval(EvalArgs),
    /// Generate a synthetic labelled set (binary PLY with a `class` property).
    ///
    /// Example: bounded generate --kind mixed -o generated/ --seed 1
    Generate(GenerateArgs),
    /// Draw a cloud as a shaded picture, coloured by class.
    ///
    /// Example: bounded render labelled.ply -o labelled.png
    Render(RenderArgs),
    /// No files needed: generate a scene, detect, write demo.ply and demo.png, print scores.
    Demo(DemoArgs),
    /// Reproduce the paper's tables next to the published peers; writes a markdown report and plots.
    Bench(BenchArgs),
}

/// Arguments of `detect`.
#[derive(Debug, Args)]
pub struct DetectArgs {
    /// Input clouds (.ply .pcd .xyz .txt .csv .las .laz .e57 .npy), or `-` for standard
    /// input (its format from its first bytes). Several (the tiles of a survey, say) get the
    /// labels of one cloud, neighbourhoods reaching across their seams: one tile at a time,
    /// with the points of its neighbours nearby, each written before the next; `--separate`
    /// labels each on its own.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Output cloud (.ply .pcd .xyz .txt .csv .las .laz .e57; the format follows the
    /// extension), `-` for standard output (in `--format`, else the input's format), or a
    /// directory (created if missing; for one input, an existing one or a path ending in /)
    /// where each input is written under its own file name.
    #[arg(short, long)]
    pub output: PathBuf,
    /// With a directory output or `-o -`: write every cloud in this format (an extension
    /// such as las or ply) instead of its input's.
    #[arg(long, value_name = "EXT")]
    pub format: Option<String>,
    #[command(flatten)]
    pub model: ModelArgs,
    /// Leave out points with a NaN or infinite coordinate (such as the invalid pixels of
    /// organised PCL clouds, or the no-return points of E57 scans) instead of refusing the
    /// file; the output holds the other points.
    #[arg(long)]
    pub drop_non_finite: bool,
    /// Label each input as a cloud of its own (separate objects or scans, even where their
    /// coordinates overlap), one after another, instead of all as one cloud. A failure stops
    /// at that input; the outputs written before it stay.
    #[arg(long)]
    pub separate: bool,
    /// A single LAS or LAZ input of more points than this is labelled in spatial blocks of
    /// about this many, each with the halo that gives it the labels of the whole file, in
    /// memory bounded by a block's (about 100 bytes a point); its output is LAS or LAZ.
    #[arg(long, default_value_t = bounded_survey::BLOCK_POINTS, value_name = "N")]
    pub block_points: usize,
    /// Where LAS/LAZ outputs put the class: `auto` (the Classification field, codes 1 / 64 /
    /// 65, unless the input's holds classes such as ground: then an extra field `class`),
    /// `classification[:NON_EDGE,SHARP,BOUNDARY]` (the input's classes kept as
    /// `input_classification`) or `extra`.
    #[arg(long, default_value = "auto")]
    pub class_to: ClassTarget,
    /// Class colours: `keep` (the input's colours stay; class colours where it has none),
    /// `replace`, or `add` (as class_red, class_green, class_blue).
    #[arg(long, default_value = "keep")]
    pub colours: Colours,
    /// Names in PLY and text outputs: `cloudcompare` (scalar_class, scalar_p_*: loaded as
    /// scalar fields), `plain` (class, p_*) or `meshlab` (plain, and p_sharp as quality).
    #[arg(long, default_value = "cloudcompare")]
    pub flavour: Flavour,
}

/// Arguments of `train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Training data: directories of labelled clouds, `abc:DIR` for ABC models (OBJ meshes
    /// beside their features YAML files), or `generated:KIND:SEED[:SHAPES]` for a synthetic
    /// set made on the fly (options after it: free-form label rules
    /// `:depth=1:angle=10:band=0.5:noise=3` and features three times the default size
    /// `:size=3`; on the mesh kinds sparse planes `:faces=3`, crease rows spread up to
    /// 1.5 times their step along the line `:rows=1.5`, blocks
    /// with 12-25 degree creases `:shallow=30`, sharp bands `:band=1.5`, a fifth of the
    /// points kept farther than 2 spacings from a crease `:sparse=0.2:dense=2`). Repeat to
    /// combine.
    #[arg(long, required = true)]
    pub data: Vec<String>,
    /// Output model file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Training iterations per run.
    #[arg(long, default_value_t = 3000)]
    pub iterations: usize,
    /// Independent runs; the one with the lowest validation loss is kept.
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// Seed of the first run (run r uses seed + r).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Neighbourhood sizes, largest first.
    #[arg(long, value_delimiter = ',', default_value = "128,64,32,16")]
    pub scales: Vec<usize>,
    /// Feature groups per scale.
    #[arg(long, value_delimiter = ',', default_value = "sigma-u,sigma-l,d,s,c")]
    pub features: Vec<FeatureGroupArg>,
    /// Output widths of the scale-fusion levels, the last repeating for deeper trees
    /// (default 12,16: with the hidden default, BoundED's network of about 1.6k parameters).
    #[arg(long, value_delimiter = ',')]
    pub fusion_widths: Option<Vec<usize>>,
    /// Widths of the classification MLP's hidden layers (default 16,16).
    #[arg(long, value_delimiter = ',')]
    pub hidden_widths: Option<Vec<usize>>,
    /// Also train a second network (auto-context) on each scale's features beside the first
    /// network's probabilities over the same neighbourhood: better on randomly sampled, noisy
    /// clouds; detection then takes about 1.2-1.4x as long (one neighbour search and one feature
    /// pass serve both networks; docs/performance.md).
    #[arg(long)]
    pub context: bool,
    /// With --context, the second network also reads where the first network's sharp
    /// probability lies as a line (its linearity, and the point's distance across and along
    /// it, per scale): one more 3x3 eigen problem per point and scale when detecting.
    #[arg(long, requires = "context")]
    pub context_line: bool,
    /// Validation clouds, given as `--data` is and never trained on, on which the default
    /// decision is chosen and recorded in the model (the sensitivity of the highest median
    /// MCC if it beats the most probable class by more than 0.01, else the most probable
    /// class). Repeat to combine; without it, the most probable class.
    #[arg(long)]
    pub calibrate_on: Vec<String>,
    /// The noise of the generated sets among `--data` and `--calibrate-on`.
    #[command(flatten)]
    pub noise: NoiseArgs,
}

/// A feature group on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FeatureGroupArg {
    /// Eigenvalues of the upper set's covariance (3).
    SigmaU,
    /// Eigenvalues of the lower set's covariance (3).
    SigmaL,
    /// Difference of the upper and lower means (2).
    D,
    /// Position of the point in its neighbourhood (2).
    S,
    /// Multi-scale centroid shift (2).
    C,
    /// How far the point lies inside the hull of its neighbours in the largest
    /// neighbourhood's tangent plane, over 32 directions (1; not in the paper).
    H,
}

/// Arguments of `eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Directory of labelled clouds (PCEDNet colours, Bazazian colours or a `class` property).
    #[arg(long)]
    pub data: PathBuf,
    /// Published peers (peers.csv) to print side by side on the same models.
    #[arg(long)]
    pub peers: Option<PathBuf>,
    /// Count PCEDNet's smooth edges as sharp instead of non-edge.
    #[arg(long)]
    pub smooth_as_sharp: bool,
    /// Positive class of the scores.
    #[arg(long, value_enum, default_value_t = PositiveArg::Sharp)]
    pub positive: PositiveArg,
}

/// The model options of `detect` and `eval`.
#[derive(Debug, Default, Args)]
pub struct ModelArgs {
    /// Model file (default: the embedded model).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Which embedded model: `row` (the default) calls one row of points along each crease,
    /// as the PCEDNet and ABC clouds are labelled; `band` calls a band 3 spacings wide, as
    /// feature curves are often labelled.
    #[arg(long, conflicts_with = "model")]
    pub embedded: Option<EmbeddedModel>,
    /// Neighbourhood sizes, largest first, overriding the model's (same count as the model's).
    #[arg(long, value_delimiter = ',')]
    pub scales: Option<Vec<usize>>,
    /// Run only the first network of a two-stage model (the embedded model has two): about
    /// 1.2-1.4x as fast (docs/performance.md), with the first network's lower quality on noisy
    /// and randomly sampled clouds.
    #[arg(long)]
    pub fast: bool,
    /// How readily a point is called a sharp edge, strictly between 0 and 1: sharp where
    /// p_sharp reaches 1 - SENSITIVITY (and p_boundary does not exceed it); `argmax`: the most
    /// probable class. Without it, the model's default, chosen on validation clouds when it
    /// was trained. `bounded eval --sensitivity` scores a choice on labelled clouds; the bench
    /// prints MCC against it for every evaluation set.
    #[arg(long)]
    pub sensitivity: Option<Decision>,
}

/// The positive class of binary scores.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PositiveArg {
    /// Sharp edges.
    Sharp,
    /// Boundaries.
    Boundary,
}

/// Arguments of `generate`.
#[derive(Debug, Args)]
pub struct GenerateArgs {
    /// Which kind of set: cad, random, boundary, mixed or freeform; options after it as for
    /// `train --data` (`freeform:depth=1:angle=10:band=1.5:noise=3:size=3`, `cad:faces=3:rows=1.5:shallow=30:band=1.5:sparse=0.2:dense=2`).
    #[arg(long, default_value = "mixed")]
    pub kind: String,
    /// Output directory (created).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Seed: the same seed gives the same files.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of shapes (default 60).
    #[arg(long)]
    pub shapes: Option<NonZeroUsize>,
    #[command(flatten)]
    pub noise: NoiseArgs,
}

/// The noise of generated clouds (`generate`, and `train`'s generated sets).
#[derive(Debug, Args)]
pub struct NoiseArgs {
    /// Noise levels, each shape drawing one: standard deviations as multiples of the cloud's
    /// median point spacing (default 0,0.1,0.2,0.4,0.6; repeat a level to draw it more often).
    #[arg(long, value_delimiter = ',')]
    pub noise: Option<Vec<f64>>,
    /// Which way the noise moves points.
    #[arg(long, value_enum, default_value_t = NoiseAlong::Any)]
    pub noise_along: NoiseAlong,
}

/// Which way generated noise moves points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum NoiseAlong {
    /// Every coordinate independently (sampling jitter).
    Any,
    /// The surface normal only (range noise of scanners, as in the noisy ABC sample).
    Normal,
}

impl From<NoiseAlong> for NoiseDirection {
    fn from(along: NoiseAlong) -> Self {
        match along {
            NoiseAlong::Any => NoiseDirection::Isotropic,
            NoiseAlong::Normal => NoiseDirection::Normal,
        }
    }
}

/// Arguments of `render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Input cloud.
    pub input: PathBuf,
    /// Output picture (.png).
    #[arg(short, long)]
    pub output: PathBuf,
    /// What the colours show.
    #[arg(long, value_enum, default_value_t = ColourBy::Class)]
    pub by: ColourBy,
    /// View direction: azimuth,elevation in degrees.
    #[arg(long, value_delimiter = ',')]
    pub view: Option<Vec<f64>>,
    /// Picture size: width,height in pixels.
    #[arg(long, value_delimiter = ',', default_value = "1024,768")]
    pub size: Vec<usize>,
}

/// What the colours of a rendering show.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ColourBy {
    /// The `class` property (as written by detect or generate).
    Class,
    /// The ground truth of a labelled dataset (PCEDNet or Bazazian colours).
    Truth,
    /// Run detection with the embedded model first.
    Detect,
}

/// Arguments of `demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Directory for demo.ply and demo.png.
    #[arg(short, long, default_value = ".")]
    pub output: PathBuf,
    /// Seed of the generated scene.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
}

/// Arguments of `bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Dataset root (holding pcednet/ and bazazian/).
    #[arg(long, default_value = "../shared/datasets")]
    pub data: PathBuf,
    /// Output directory for report.md and the plots.
    #[arg(short, long, default_value = "bench-report")]
    pub output: PathBuf,
    /// Fewer iterations and runs: about 10 minutes on 2 cores.
    #[arg(long)]
    pub quick: bool,
}
