//! `bounded bench`: the paper's evaluation, reproduced side by side with the published peers.
//!
//! Features are computed once per cloud at the 16 scales of the scale ablation with every
//! feature group; every table selects its columns from them (the nested kNN sets make a
//! smaller configuration's features exactly a subset), so the ablations cost only training.

use super::{load_set, peer_methods, rate, training_clouds};
use crate::cli::BenchArgs;
use crate::pipeline;
use crate::progress::FitBars;
use anyhow::{Context, Result, bail};
use bounded_data::LabelledCloud;
use bounded_data::peers;
use bounded_data::picture::{Canvas, PALETTE, Series, View, precision_recall, render_classes};
use bounded_data::synth::{self, NoiseDirection, SetConfig, SetKind, recipe};
use bounded_features::{FeatureConfig, FeatureGroups};
use bounded_geom::Class;
use bounded_nn::baseline::CaBaseline;
use bounded_nn::calibration::{self, with_chosen_sensitivity};
use bounded_nn::fit::{self, FeatureSet, Schedule, Seconds, Widths, columns};
use bounded_nn::report::{
    self, FeaturedCloud, MethodResults, ModelResult, confusion_table, median_scores, medians_table,
    per_model_table, pooled,
};
use bounded_nn::{Classifier, Detector, EmbeddedModel};
use std::fmt::Write;
use std::path::Path;
use std::time::Instant;

/// The generated boundary evaluation set: its own seed, never used for training.
const BOUNDARY_EVAL: (u64, usize) = (1001, 30);

/// The generated free-form feature-curve set: its own seed, never used for training.
const FREEFORM_EVAL: (u64, usize) = (1003, 30);

/// The generated CAD sets of the noise sweep: their own seed, never used for training.
const NOISE_EVAL: (u64, usize) = (1002, 30);

/// The noise sweep: standard deviations in spacings and their direction.
const NOISE_SWEEP: [(f64, NoiseDirection); 6] = [
    (0.0, NoiseDirection::Normal),
    (0.25, NoiseDirection::Normal),
    (0.5, NoiseDirection::Normal),
    (0.75, NoiseDirection::Normal),
    (1.0, NoiseDirection::Normal),
    (0.5, NoiseDirection::Isotropic),
];

/// One evaluation set.
struct EvalSet {
    /// Directory or set name, also the peers.csv dataset key.
    key: &'static str,
    clouds: Vec<FeaturedCloud>,
}

pub fn run(args: &BenchArgs) -> Result<()> {
    let start = Instant::now();
    // SPEC.md: 8000 iterations for ABC-size training sets (ours holds 6.6M points, 410 clouds).
    let (iterations, runs) = if args.quick {
        (1000, 1)
    } else {
        (8000, recipe::RUNS)
    };
    let schedule = Schedule {
        iterations,
        runs,
        seed: 1,
    };
    let ablation_schedule = Schedule {
        runs: 1,
        ..schedule
    };
    // At 16 scales with 13 features and two runs per stage (2026-12-07): full mode took 86.1
    // minutes (13.5 GiB peak, in the single-stage ablations), 32 of them training the main
    // model; the ablations, one run at a time, take most of the rest (docs/performance.md).
    let (mode, duration) = if args.quick {
        ("quick", "about 10 minutes")
    } else {
        ("full", "1.5 hours")
    };
    eprintln!(
        "bench: {mode} mode, expected duration {duration} on 2 cores (full mode peaks near 14.5 GB of memory)"
    );
    let pcednet = args.data.join("pcednet");
    let peers_path = pcednet.join("peers.csv");
    let peers = peers::read(&peers_path)?;
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("cannot create {}", args.output.display()))?;

    // Training data.
    let training = recipe::generate(&recipe::TRAINING_SETS, if args.quick { 4 } else { 1 })?;

    let full = FeatureConfig::ablation(16, FeatureGroups::ALL)?;
    // The embedded model's feature extraction (its scales, groups and context), retrained.
    let main = Detector::embedded()?.feature_config().clone();
    let mut report = String::from("# BoundED-rs bench\n\n");
    let _ = writeln!(
        report,
        "Mode: {}; {} iterations, best of {} runs for each of the main model's two stages \
         (the second auto-context; ablations: single-stage, 1 run). \
         Training data: {} with noise levels {:?} spacings along {} ({} clouds, {} points). \
         Evaluation data is never trained on.\n",
        mode,
        schedule.iterations,
        schedule.runs,
        recipe::TRAINING_SETS.join(", "),
        recipe::TRAINING_NOISE,
        recipe::TRAINING_NOISE_ALONG.phrase(),
        training.len(),
        training.iter().map(|c| c.1.cloud.len()).sum::<usize>()
    );

    // Timing of the default configuration, as the paper's timing table.
    let (main_file, train_seconds) = FitBars::around(|progress| {
        let clouds = training_clouds(&training);
        let command = "bounded bench".into();
        fit::fit_stages(
            &clouds,
            &main,
            &schedule,
            &Widths::default(),
            true,
            command,
            progress,
        )
    })?;
    let validation = recipe::generate(&recipe::VALIDATION_SETS, 1)?;
    let (main_file, on_validation) =
        with_chosen_sensitivity(main_file, &training_clouds(&validation))?;
    drop(validation);
    if !args.quick {
        let _ = writeln!(
            report,
            "The main model {} the embedded default model (weights, standardisation, data \
             hash and validation loss of both stages, and the sensitivity, compared).\n",
            if main_file.same_model(bounded_nn::default_model()?.file()) {
                "reproduces"
            } else {
                "**differs from**"
            }
        );
    }
    // The ablations are single-stage: the main model's first stage is their reference.
    let first_stage = Classifier::from_file(main_file.first_stage())?;
    let detector = Detector::new(Classifier::from_file(main_file)?)?;
    let ours_scorer = Scorer::Detector(&detector);

    let train_full = FitBars::around(|progress| {
        fit::feature_set(&training_clouds(&training), &full, None, progress)
    })?;
    drop(training);
    let sets = [
        load_eval(&pcednet.join("default"), "default", &full)?,
        load_eval(&pcednet.join("abc"), "abc", &full)?,
        load_eval(&pcednet.join("abc_noise_0.04"), "abc_noise_0.04", &full)?,
        generated_eval(
            "boundary",
            &SetConfig::new(SetKind::Boundary, BOUNDARY_EVAL.0, BOUNDARY_EVAL.1),
            &full,
        )?,
        generated_eval(
            "freeform",
            &SetConfig::new(SetKind::Freeform, FREEFORM_EVAL.0, FREEFORM_EVAL.1),
            &full,
        )?,
    ];

    // 1-2: main tables with peers, and our CA.
    let ca = CaBaseline::fit(&train_full, &full, &main.scales)?;
    for set in &sets[..2] {
        let ours = score(&ours_scorer, &full, set)?;
        let mut methods = vec![MethodResults::of("BoundED-rs (ours)", &ours, Class::Sharp)];
        methods.push(ca.results("CA-rs (surface variation, ours)", &set.clouds)?);
        let models: Vec<String> = set.clouds.iter().map(|c| c.name.clone()).collect();
        methods.extend(peer_methods(&peers, set.key, &models));
        let _ = writeln!(
            report,
            "## {} evaluation set ({} models): medians, sharp edge positive\n\n{}",
            set.key,
            set.clouds.len(),
            medians_table(&methods)
        );
        let _ = writeln!(
            report,
            "Peers from {}; `sharp+smooth` peers counted smooth edges as positive. {}. \
             The paper reports BoundED MCC 0.423 (Default, trained on Default) and 0.842 \
             (ABC, trained on ABC, all 7168 models).\n\n{}\n",
            peers_path.display(),
            format_args!(
                "CA-rs: surface variation at k = {} above {:.3} (fitted on the training set)",
                ca.scale, ca.threshold
            ),
            per_model_table(&methods[0])
        );
        let png = args.output.join(format!("pr_{}.png", set.key));
        pr_plot(&format!("{}: precision vs recall", set.key), &methods).save_png(&png)?;
        let _ = writeln!(report, "![{}](pr_{}.png)\n", set.key, set.key);
    }

    // 3: timing.
    report.push_str(&timing_table(&detector, &args.data, &train_seconds)?);

    // 4: ablations, single-stage, around SPEC.md's 4 scales; the main model's configuration
    // reuses its first stage, and the 4-scale one (three tables' reference) is trained once.
    let train = |target: &FeatureConfig, widths: &Widths| {
        trained(&train_full, &full, target, &ablation_schedule, widths)
    };
    let four = FeatureConfig::default();
    let reference = train(&four, &Widths::default())?;
    let ablation = |label: &str, target: &FeatureConfig, widths: &Widths| -> Result<String> {
        let ablated;
        // Single-stage: the context does not matter.
        let is = |c: &FeatureConfig| {
            target.scales == c.scales && target.groups == c.groups && *widths == Widths::default()
        };
        let model = if is(&main) {
            &first_stage
        } else if is(&four) {
            &reference
        } else {
            ablated = train(target, widths)?;
            &ablated
        };
        let scorer = Scorer::Columns { model, target };
        ablation_row(label, &scorer, &full, &sets)
    };
    report.push_str("## Feature ablation (4 scales)\n\n| features | Default MCC | Default F1 | ABC MCC | ABC F1 | noisy ABC MCC |\n|---|---|---|---|---|---|\n");
    for (label, groups) in FeatureGroups::ABLATION {
        let target = FeatureConfig {
            groups,
            ..FeatureConfig::default()
        };
        report.push_str(&ablation(label, &target, &Widths::default())?);
    }
    report.push_str("\n## Scale ablation (all features)\n\n| scales | Default MCC | Default F1 | ABC MCC | ABC F1 | noisy ABC MCC |\n|---|---|---|---|---|---|\n");
    for count in [2, 4, 8, 16] {
        let target = FeatureConfig::ablation(count, FeatureGroups::BOUNDED)?;
        report.push_str(&ablation(
            &format!("{count}: {:?}", target.scales),
            &target,
            &Widths::default(),
        )?);
    }
    report.push_str("\n## Width ablation (4 scales, all features)\n\n| fusion / hidden widths | Default MCC | Default F1 | ABC MCC | ABC F1 | noisy ABC MCC |\n|---|---|---|---|---|---|\n");
    for widths in Widths::ablations() {
        let label = format!(
            "{:?} / {:?} ({} parameters)",
            widths.fusion,
            widths.hidden,
            widths.model(&four, false).n_params()
        );
        report.push_str(&ablation(&label, &four, &widths)?);
    }
    let main_file = detector.classifier().file();
    let second = main_file.second_stage.as_deref();
    let label = format!(
        "{:?} / {:?} at 16 scales and an auto-context second stage ({} parameters; the main model)",
        Widths::default().fusion,
        Widths::default().hidden,
        main_file.model.n_params() + second.map_or(0, |f| f.model.n_params())
    );
    report.push_str(&ablation_row(&label, &ours_scorer, &full, &sets)?);

    // 5: noise and boundaries.
    let clean = score(&ours_scorer, &full, &sets[1])?;
    let noisy = score(&ours_scorer, &full, &sets[2])?;
    let mcc = |r: &[ModelResult]| median_scores(r, Class::Sharp).map_or(f64::NAN, |s| s.mcc);
    let _ = writeln!(
        report,
        "\n## Noise\n\nMedian MCC (sharp): clean ABC {:.3}, noisy ABC (abc_noise_0.04) {:.3}, \
         difference {:.3}.\n",
        mcc(&clean),
        mcc(&noisy),
        mcc(&clean) - mcc(&noisy)
    );
    let _ = writeln!(
        report,
        "Generated CAD clouds (seed {}, {} clouds, never trained on; the noisy ABC sample \
         has about 0.5 along the normal), sharp edge positive:\n\n\
         | noise (spacings) | along | MCC | F1 |\n|---|---|---|---|",
        NOISE_EVAL.0, NOISE_EVAL.1
    );
    for (level, direction) in NOISE_SWEEP {
        // The noise sweep's CAD set at one noise level, without outliers.
        let mut config = SetConfig::new(SetKind::Cad, NOISE_EVAL.0, NOISE_EVAL.1);
        config.outlier_fraction = 0.0;
        let config = config.with_noise(Some(&[level]), direction)?;
        let set = generated_eval("noise", &config, &full)?;
        let (sweep_mcc, sweep_f1) = median_scores(&score(&ours_scorer, &full, &set)?, Class::Sharp)
            .map_or((f64::NAN, f64::NAN), |s| (s.mcc, s.f1));
        let _ = writeln!(
            report,
            "| {level} | {} | {sweep_mcc:.3} | {sweep_f1:.3} |",
            direction.phrase()
        );
    }
    report.push('\n');
    let boundary = score(&ours_scorer, &full, &sets[3])?;
    let b = MethodResults::of("BoundED-rs (ours)", &boundary, Class::Boundary);
    let open = b.with_positives("BoundED-rs (ours), the clouds with boundaries");
    let boundary_f1 = pooled(&boundary).binary(Class::Boundary as u8).f1();
    let _ = writeln!(
        report,
        "## Boundaries (generated set, seed {}, {} clouds, never trained on)\n\n\
         Boundary positive (a closed shape, without boundary points, scores 1 where none is \
         found: the second row leaves those out):\n\n{}\nBoundary F1 over all points: {:.3}. \
         3-class confusion, all clouds:\n\n{}",
        BOUNDARY_EVAL.0,
        BOUNDARY_EVAL.1,
        medians_table(&[b, open]),
        boundary_f1,
        confusion_table(&boundary)
    );
    let freeform = score(&ours_scorer, &full, &sets[4])?;
    let rule = SetConfig::new(SetKind::Freeform, FREEFORM_EVAL.0, FREEFORM_EVAL.1).label_rule;
    let _ = writeln!(
        report,
        "\n## Free-form feature curves (generated freeform set, seed {}, {} clouds, never \
         trained on)\n\nGrooves, ridges, steps and creases along curves on free-form surfaces; \
         sharp where a kink deviates by at least {} degrees and displaces by at least {} \
         spacings, labelled in a band of {} spacings either side of the kink line. Sharp edge \
         positive:\n\n{}",
        FREEFORM_EVAL.0,
        FREEFORM_EVAL.1,
        rule.min_angle,
        rule.min_depth,
        rule.band,
        medians_table(&[MethodResults::of(
            "BoundED-rs (ours)",
            &freeform,
            Class::Sharp
        )])
    );
    let band = Detector::embedded_model(EmbeddedModel::Band)?;
    report.push_str(&band_section(&detector, &band, boundary_f1, &sets[3])?);
    report.push_str(&calibration::section(
        &detector,
        &recipe::VALIDATION_SETS.join(", "),
        on_validation,
        &(sets.iter())
            .map(|s| {
                (
                    s.key,
                    s.clouds.iter().map(FeaturedCloud::labelled).collect(),
                )
            })
            .collect::<Vec<_>>(),
    )?);
    report.push_str(&scans_section(&detector, &band, &args.data, &args.output)?);
    let _ = writeln!(
        report,
        "\nBench wall time: {:.1} min.",
        start.elapsed().as_secs_f64() / 60.0
    );
    let path = args.output.join("report.md");
    bounded_geom::atomic::write(&path, report.as_bytes())?;
    println!("{report}");
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// The sets of the band section: never trained on by either embedded model, labelled in bands
/// (`band=`; the free-form kind's default is 1) and in one row. The free-form set with
/// features three times the default size (`size=3`, at least a spacing deep) is the generated
/// set closest to issue 31's held-out clouds (docs/model.md, 2026-12-06).
const BAND_SETS: [&str; 6] = [
    "generated:freeform:1003:30",
    "generated:freeform:1003:30:band=1.5",
    "generated:freeform:1003:30:depth=1:size=3",
    "generated:cad:1002:30:band=1.5",
    "generated:cad:1002:30",
    "generated:random:1002:30:band=1.5",
];

/// The embedded band model `band`, as shipped, beside the main model (`main`, boundary F1
/// `main_boundary_f1` on the boundary set `boundary`) on [`BAND_SETS`].
fn band_section(
    main: &Detector,
    band: &Detector,
    main_boundary_f1: f64,
    boundary: &EvalSet,
) -> Result<String> {
    let mut methods = Vec::new();
    for spec in BAND_SETS {
        let clouds = synth::generate(&SetConfig::from_spec(spec)?)?;
        for (name, detector) in [("main", main), ("band", band)] {
            let results = report::evaluate(detector, &training_clouds(&clouds), &mut |_, _| {})?;
            let name = format!("{name} model, {spec}");
            methods.push(MethodResults::of(&name, &results, Class::Sharp));
        }
    }
    let clouds: Vec<_> = boundary
        .clouds
        .iter()
        .map(FeaturedCloud::labelled)
        .collect();
    let band_boundary = report::evaluate(band, &clouds, &mut |_, _| {})?;
    Ok(format!(
        "\n## The band model (`--embedded band`)\n\nThe second embedded model, as shipped (trained \
         by the command in docs/model.md, not here), calls every point within 1.5 spacings of \
         a crease or feature curve sharp. Beside the main model on generated sets that neither \
         was trained on, labelled in bands (`band=` spacings either side; the free-form \
         kind's default is 1) and in one row; `size=3` draws every free-form feature three \
         times the default size, the generated set closest to the held-out clouds that issue \
         31 describes (docs/model.md). Sharp edge positive:\n\n{}\nBoundary F1 over \
         all points of the boundary set (seed {}): main model {main_boundary_f1:.3}, band \
         model {:.3}.\n\n",
        medians_table(&methods),
        BOUNDARY_EVAL.0,
        pooled(&band_boundary).binary(Class::Boundary as u8).f1()
    ))
}

/// The unlabelled real scans of `data/scans`, pictured before and after detection by the main
/// model `detector` and by the embedded band model `band`.
fn scans_section(
    detector: &Detector,
    band: &Detector,
    data: &Path,
    output: &Path,
) -> Result<String> {
    let mut out = String::from(
        "\n## Real scans (no labels): before and after detection (main model, band model)\n\n",
    );
    let view = View::default();
    for name in ["room_scan1", "CSite1_red1-utm"] {
        let cloud = bounded_data::format::read(&data.join(format!("scans/{name}.pcd")))?.cloud;
        let before = vec![Class::NonEdge; cloud.len()];
        let after = detector.detect(&cloud)?.classes;
        let band = band.detect(&cloud)?.classes;
        let _ = write!(out, "{name}.pcd, {} points:", cloud.len());
        for (side, classes) in [("before", before), ("after", after), ("band", band)] {
            let file = format!("scan_{name}_{side}.png");
            render_classes(&cloud, &classes, view, 1024, 768).save_png(&output.join(&file))?;
            let _ = write!(out, " ![{side}]({file})");
        }
        out.push_str("\n\n");
    }
    Ok(out)
}

fn trained(
    set: &FeatureSet,
    full: &FeatureConfig,
    target: &FeatureConfig,
    schedule: &Schedule,
    widths: &Widths,
) -> Result<Classifier> {
    let selected = set.select(&columns(full, target)?);
    let command = "bounded bench (ablation)".into();
    let file = FitBars::around(|progress| {
        fit::fit(&selected, target, schedule, widths, command, progress)
    })?;
    Ok(Classifier::from_file(file)?)
}

/// The clouds with their features at the full configuration, with a progress bar each.
fn featured(
    clouds: Vec<(String, LabelledCloud)>,
    full: &FeatureConfig,
) -> Result<Vec<FeaturedCloud>> {
    (clouds.into_iter())
        .map(|(name, c)| {
            let featured = FitBars::around(|progress| {
                FeaturedCloud::new(name, c.cloud, c.labels, full, progress)
            });
            Ok(featured?)
        })
        .collect()
}

fn load_eval(dir: &Path, key: &'static str, full: &FeatureConfig) -> Result<EvalSet> {
    if !dir.is_dir() {
        bail!("{}: evaluation set missing (see --data)", dir.display());
    }
    let clouds = featured(load_set(dir, Class::NonEdge)?, full)?;
    Ok(EvalSet { key, clouds })
}

/// The generated evaluation set `config`, called `key`.
fn generated_eval(key: &'static str, config: &SetConfig, full: &FeatureConfig) -> Result<EvalSet> {
    let clouds = featured(synth::generate(config)?, full)?;
    Ok(EvalSet { key, clouds })
}

/// What the bench scores: the main model through the library detector, or a one-stage
/// ablation model over its columns of the precomputed features.
enum Scorer<'a> {
    Detector(&'a Detector),
    Columns {
        model: &'a Classifier,
        target: &'a FeatureConfig,
    },
}

/// Classifies every cloud of `set` with `scorer` (its features computed with `full`).
fn score(scorer: &Scorer<'_>, full: &FeatureConfig, set: &EvalSet) -> Result<Vec<ModelResult>> {
    match scorer {
        Scorer::Detector(detector) => {
            let clouds: Vec<_> = set.clouds.iter().map(FeaturedCloud::labelled).collect();
            Ok(report::evaluate(detector, &clouds, &mut |_, _| {})?)
        }
        Scorer::Columns { model, target } => {
            let columns = columns(full, target)?;
            let scored = set.clouds.iter().map(|c| c.classify(model, &columns));
            Ok(scored.collect::<Result<_, _>>()?)
        }
    }
}

fn ablation_row(
    label: &str,
    scorer: &Scorer<'_>,
    full: &FeatureConfig,
    sets: &[EvalSet],
) -> Result<String> {
    let mut row = format!("| {label} |");
    // Default and ABC: MCC and F1; noisy ABC: MCC, to show what each ablation does to the
    // noise gap.
    for (k, set) in sets[..3].iter().enumerate() {
        let s = median_scores(&score(scorer, full, set)?, Class::Sharp)
            .context("empty evaluation set")?;
        let _ = write!(row, " {:.3} |", s.mcc);
        if k < 2 {
            let _ = write!(row, " {:.3} |", s.f1);
        }
    }
    row.push('\n');
    Ok(row)
}

/// Timing of the default configuration: training preprocessing and training, then features
/// and classification on each PCEDNet evaluation set (through the streaming detector).
fn timing_table(detector: &Detector, data: &Path, train: &Seconds) -> Result<String> {
    let mut out = format!(
        "## Timing (2 cores, CPU only)\n\nTraining (both stages): features {:.1} s, \
         training {:.1} s.\n\n| set | points | features + kNN s | classification s | points/s |\n\
         |---|---|---|---|---|\n",
        train.features, train.training
    );
    for key in ["default", "abc"] {
        let clouds = load_set(&data.join("pcednet").join(key), Class::NonEdge)?;
        let (mut points, mut total, mut classification) = (0, 0.0, 0.0);
        for (name, labelled) in &clouds {
            let d =
                pipeline::detect(detector, &labelled.cloud, false).with_context(|| name.clone())?;
            points += labelled.cloud.len();
            total += d.elapsed.as_secs_f64();
            classification += d.classification.as_secs_f64();
        }
        let _ = writeln!(
            out,
            "| {key} | {points} | {:.2} | {classification:.3} | {} |",
            total - classification,
            rate(points, total)
        );
    }
    out.push('\n');
    Ok(out)
}

/// A precision-recall scatter plot of the methods.
fn pr_plot(title: &str, methods: &[MethodResults]) -> Canvas {
    let series = |(i, m): (usize, &MethodResults)| Series {
        name: m.name.clone(),
        colour: PALETTE[i % PALETTE.len()],
        points: m.recall_precision(),
    };
    precision_recall(
        title,
        &methods.iter().enumerate().map(series).collect::<Vec<_>>(),
    )
}
