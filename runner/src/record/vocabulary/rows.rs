//! The rows of the metric vocabulary: each metric a mode's record holds, with how it is read,
//! gated, tabled, plotted and ranked. The kinds of its fields, the formatters its cells use and
//! the lookups over it are in `mod.rs`.

use super::*;
use crate::manifest::tolerances::Tolerance;

/// The still's PSNR against the truth: what the still's ranking orders modes by.
pub const PSNR_VS_TRUTH: Metric = Metric {
    id: "psnr_vs_truth",
    label: "PSNR against the truth",
    source: Source::Truth,
    read: Read::Mode(|mode| Some(mode.vs_ground_truth.as_ref()?.psnr_db.value())),
    gate: Some(Gate { rule: DECIBELS, tolerance: Tolerance::PsnrDb, show: decibels_3 }),
    column: Some(Column { table: Table::Still, header: "PSNR vs truth", cell: decibels }),
    plot: None,
    brief: Some(|db| format!("PSNR {} dB", decibels(db))),
    front_margin: Some(PSNR_MARGIN_DB),
};

/// The still's FLIP against the truth.
pub const FLIP_VS_TRUTH: Metric = Metric {
    id: "flip_vs_truth",
    label: "FLIP against the truth",
    source: Source::Truth,
    read: Read::Mode(|mode| mode.vs_ground_truth.as_ref()?.flip),
    gate: Some(Gate { rule: ERROR, tolerance: Tolerance::FlipRelative, show: five_decimals }),
    column: Some(Column { table: Table::Still, header: "FLIP vs truth", cell: four_decimals }),
    plot: Some(Plot {
        title: "FLIP against run time",
        axis: "mean FLIP against the truth (log)",
        axis_value: |v| v,
        file: "front-flip",
        front: Front::Medians,
    }),
    brief: Some(|flip| format!("FLIP {flip:.4}")),
    front_margin: None,
};

/// The still's ColorVideoVDP score against the truth, in JOD: what the still's ranking orders
/// modes by where there is no path.
pub const JOD_VS_TRUTH: Metric = Metric {
    id: "jod_vs_truth",
    label: "JOD against the truth",
    source: Source::Truth,
    read: Read::Mode(|mode| mode.vs_ground_truth.as_ref()?.jod),
    gate: Some(Gate { rule: JOD, tolerance: Tolerance::Jod, show: jod }),
    column: Some(Column { table: Table::Still, header: "JOD vs truth", cell: jod }),
    plot: Some(Plot {
        title: "JOD against run time",
        axis: "JOD below 10 against the truth (log)",
        axis_value: jod_loss,
        file: "front-jod",
        front: Front::Recorded("jod_vs_truth"),
    }),
    brief: None,
    front_margin: Some(JOD_MARGIN),
};

/// ColorVideoVDP along a camera path against the truth's frames: what a path's ranking orders
/// modes by.
pub const SEQUENCE_JOD_VS_TRUTH: Metric = Metric {
    id: "sequence_jod_vs_truth",
    label: "JOD against the truth's frames",
    source: Source::Sequence,
    read: Read::Along(|sequence| sequence.jod),
    gate: Some(Gate { rule: JOD, tolerance: Tolerance::Jod, show: jod }),
    column: Some(Column { table: Table::Path, header: "JOD along the path", cell: jod }),
    plot: Some(Plot {
        title: "JOD in motion against run time",
        axis: "JOD below 10 along the camera path (log)",
        axis_value: jod_loss,
        file: "front-jod-path",
        front: Front::Recorded("sequence_jod_vs_truth"),
    }),
    brief: None,
    front_margin: Some(JOD_MARGIN),
};

/// The mean PSNR along a camera path.
pub const SEQUENCE_PSNR_VS_TRUTH: Metric = Metric {
    id: "sequence_psnr_vs_truth",
    label: "mean PSNR against the truth's frames",
    source: Source::Sequence,
    read: Read::Along(|sequence| Some(sequence.mean_psnr_db.value())),
    gate: Some(Gate { rule: DECIBELS, tolerance: Tolerance::PsnrDb, show: decibels_3 }),
    column: Some(Column { table: Table::Path, header: "PSNR along the path", cell: decibels }),
    plot: None,
    brief: Some(|db| format!("PSNR {} dB", decibels(db))),
    front_margin: None,
};

/// Every metric, in the order of the report's columns within each table (the gate checks them
/// in this order too).
pub const METRICS: [Metric; 23] = [
    Metric {
        id: "shaded_percent",
        label: "samples shaded",
        source: Source::Samples,
        read: Read::Mode(|mode| Some(mode.samples.as_ref()?.shaded_percent)),
        gate: Some(Gate { rule: Rule::Points, tolerance: Tolerance::ShadedPercent, show: percent }),
        column: Some(Column { table: Table::Still, header: "samples %", cell: one_decimal }),
        plot: None,
        brief: None,
        front_margin: None,
    },
    Metric {
        id: "mse_vs_truth",
        label: "MSE against the truth",
        source: Source::Truth,
        read: Read::Mode(|mode| Some(mode.vs_ground_truth.as_ref()?.mse)),
        gate: Some(Gate { rule: ERROR, tolerance: Tolerance::MseRelative, show: mse_e5 }),
        column: Some(Column {
            table: Table::Still,
            header: "MSE ×1e-5 vs truth",
            cell: |v| format!("{:.3}", v * 1e5),
        }),
        plot: Some(Plot {
            title: "error against run time",
            axis: "MSE against the truth ×1e-5 (log)",
            axis_value: |v| v * 1e5,
            file: "front",
            // PSNR is MSE's on a log scale: one order, one front.
            front: Front::Recorded("psnr_vs_truth"),
        }),
        brief: None,
        front_margin: None,
    },
    Metric {
        id: "psnr_vs_reference",
        label: "PSNR against the reference",
        source: Source::Reference,
        read: Read::Mode(|mode| Some(mode.vs_reference.as_ref()?.psnr_db.value())),
        gate: Some(Gate { rule: DECIBELS, tolerance: Tolerance::PsnrDb, show: decibels_3 }),
        column: Some(Column { table: Table::Still, header: "PSNR vs ref", cell: decibels }),
        plot: None,
        brief: None,
        front_margin: None,
    },
    PSNR_VS_TRUTH,
    JOD_VS_TRUTH,
    FLIP_VS_TRUTH,
    Metric {
        id: "ssim_vs_truth",
        label: "SSIM against the truth",
        source: Source::Truth,
        read: Read::Mode(|mode| mode.vs_ground_truth.as_ref()?.ssim),
        gate: Some(Gate {
            rule: Rule::Relative { perfect: 1.0 },
            tolerance: Tolerance::SsimRelative,
            show: five_decimals,
        }),
        column: Some(Column { table: Table::Still, header: "SSIM vs truth", cell: four_decimals }),
        plot: None,
        brief: None,
        front_margin: None,
    },
    Metric {
        id: "mse_vs_reference",
        label: "MSE against the reference",
        source: Source::Reference,
        read: Read::Mode(|mode| Some(mode.vs_reference.as_ref()?.mse)),
        gate: Some(Gate { rule: ERROR, tolerance: Tolerance::MseRelative, show: mse_e5 }),
        column: None,
        plot: None,
        brief: None,
        front_margin: None,
    },
    Metric {
        id: "sequence_shaded_percent",
        label: "samples shaded along the path",
        source: Source::Sequence,
        read: Read::Along(|sequence| sequence.shaded_percent),
        gate: Some(Gate { rule: Rule::Points, tolerance: Tolerance::ShadedPercent, show: percent }),
        column: Some(Column { table: Table::Path, header: "samples %", cell: one_decimal }),
        plot: None,
        brief: None,
        front_margin: None,
    },
    SEQUENCE_JOD_VS_TRUTH,
    SEQUENCE_PSNR_VS_TRUTH,
    Metric {
        id: "sequence_flip_vs_truth",
        label: "mean FLIP against the truth's frames",
        source: Source::Sequence,
        read: Read::Along(|sequence| sequence.mean_flip),
        gate: Some(Gate { rule: ERROR, tolerance: Tolerance::FlipRelative, show: five_decimals }),
        column: Some(Column { table: Table::Path, header: "FLIP along the path", cell: four_decimals }),
        plot: None,
        brief: Some(|flip| format!("FLIP {flip:.4}")),
        front_margin: None,
    },
    Metric {
        // An error of squared code values, as MSE is: the MSE tolerance.
        id: "flicker",
        label: "flicker along the truth's motion",
        source: Source::Sequence,
        read: Read::Along(|sequence| sequence.flicker),
        gate: Some(Gate { rule: ERROR, tolerance: Tolerance::MseRelative, show: |v| format!("{v:.4e}") }),
        column: Some(Column {
            table: Table::Path,
            header: "flicker ×1e-4",
            cell: |v| format!("{:.3}", v * 1e4),
        }),
        plot: Some(Plot {
            title: "flicker against run time",
            axis: "flicker along the camera path (log)",
            axis_value: |v| v,
            file: "front-flicker",
            // A front of flicker against time promotes blur and lag, which flicker little.
            front: Front::None,
        }),
        brief: Some(|v| format!("flicker {:.2}e-4", v * 1e4)),
        front_margin: None,
    },
    Metric {
        // What lag costs where history cannot help: an error of squared code values, as MSE is.
        id: "disoccluded_mse",
        label: "MSE where the frame before had the surface hidden",
        source: Source::Sequence,
        read: Read::Along(|sequence| sequence.ghosting.as_ref()?.mse),
        gate: Some(Gate { rule: ERROR, tolerance: Tolerance::MseRelative, show: |v| format!("{v:.4e}") }),
        column: Some(Column { table: Table::Path, header: "MSE disoccluded ×1e-3", cell: thousandths }),
        plot: None,
        brief: Some(|v| format!("disoccluded MSE {:.2}e-3", v * 1e3)),
        front_margin: None,
    },
    Metric {
        // Without motion compensation it rewards lag and blur: gated, not shown.
        id: "instability",
        label: "uncompensated change of error",
        source: Source::Sequence,
        read: Read::Along(|sequence| Some(sequence.instability)),
        gate: Some(Gate { rule: ERROR, tolerance: Tolerance::MseRelative, show: |v| format!("{v:.4e}") }),
        column: None,
        plot: None,
        brief: None,
        front_margin: None,
    },
    Metric {
        id: "change_ratio",
        label: "the mode's own change from frame to frame over the truth's",
        source: Source::Sequence,
        read: Read::Along(|sequence| sequence.change_ratio),
        gate: None,
        column: Some(Column { table: Table::Path, header: "change ratio", cell: two_decimals }),
        plot: None,
        brief: None,
        front_margin: None,
    },
    Metric {
        id: "count_changes",
        label: "the share of pixels whose sample count changes from frame to frame",
        source: Source::Sequence,
        read: Read::Along(|sequence| sequence.count_changes),
        gate: None,
        column: Some(Column {
            table: Table::Path,
            header: "count changes %",
            cell: |v| format!("{:.2}", v * 100.0),
        }),
        plot: None,
        brief: None,
        front_margin: None,
    },
    lag_row(
        "disoccluded_share",
        "share of pixels whose surface the frame before had hidden",
        |sequence| Some(sequence.ghosting.as_ref()?.disoccluded),
        "disoccluded %",
        hundredths_of_percent,
    ),
    lag_row(
        "entered_share",
        "share of pixels whose surface entered from off the frame before",
        |sequence| Some(sequence.ghosting.as_ref()?.entered),
        "entered %",
        hundredths_of_percent,
    ),
    lag_row(
        "entered_mse",
        "MSE where the surface entered from off the frame before",
        |sequence| sequence.ghosting.as_ref()?.mse_entered,
        "MSE entered ×1e-3",
        thousandths,
    ),
    lag_row(
        "moving_edges_mse",
        "MSE at and beside the silhouettes that moved",
        |sequence| sequence.ghosting.as_ref()?.mse_edges,
        "MSE at moving edges ×1e-3",
        thousandths,
    ),
    lag_row(
        "elsewhere_mse",
        "MSE away from disocclusions and moving silhouettes",
        |sequence| sequence.ghosting.as_ref()?.mse_elsewhere,
        "MSE elsewhere ×1e-3",
        thousandths,
    ),
    Metric {
        // Why a viewer and squared error disagree: the eye sees coarse error far better than
        // pixel-scale error of the same energy (`measure::pixels::coarse_share`).
        id: "coarse_share",
        label: "share of the error's energy a blur of σ 2 px keeps, where the modes flicker most",
        source: Source::Sequence,
        read: Read::Along(|sequence| sequence.coarse_share),
        gate: None,
        column: Some(Column {
            table: Table::Path,
            header: "coarse error %",
            cell: |v| format!("{:.0}", v * 100.0),
        }),
        plot: None,
        brief: None,
        front_margin: None,
    },
];

/// A row of what lag costs, from the sequence's ghosting (`measure::temporal`): shown in the
/// path's table, not gated (the gate guards lag through `disoccluded_mse`).
const fn lag_row(
    id: &'static str,
    label: &'static str,
    read: fn(&ModeSequence) -> Option<f64>,
    header: &'static str,
    cell: fn(f64) -> String,
) -> Metric {
    Metric {
        id,
        label,
        source: Source::Sequence,
        read: Read::Along(read),
        gate: None,
        column: Some(Column { table: Table::Path, header, cell }),
        plot: None,
        brief: None,
        front_margin: None,
    }
}
