//! Int8 quantization of a trained network and its export as a weights blob
//! ([`posecoach_core::weights`]), which [`posecoach_core::network`] runs.
//!
//! - **Weights**: symmetric per output channel, `scale = max |w| / 127`. A layer whose int8
//!   input has one scale per channel (the motion features) has those scales folded into its
//!   weights first, so its accumulators share one unit per output.
//! - **Activations**: one scale per point ([`Point`](crate::calibration::Point)), the largest
//!   magnitude the float network produces there on golf windows ([`calibrate`]) over 127.
//! - **Constants** fold into biases: the time encoding (one bias row per frame), the segment
//!   tokens' residual (one row per segment), and the rest features' columns of the first
//!   joint layers (per joint, by the core at set-up).
//! - **Attention**: a token's query is constant, so its logit for a joint is the key layer
//!   seen through the query, one `f32` row per token and head ([`Table::JointLogits`]); keys
//!   are never computed. The tokens' own logits and values are `f32` tables too.

use crate::bodies::Variation;
use crate::calibration::{Calibration, TINY};
use crate::dataset::{Pool, Split, SplitRng, Structure, FORMATS};
use crate::error::Error;
use crate::features::{Batch, Window, MOTION_CHANNELS, RATE_HZ, WINDOW};
use crate::model::{Dense as Layer, Parameters, Teacher, TeacherConfig};
use crate::prior::PriorKind;
use crate::skeletons::{REST_CHANNELS, SEGMENTS};
use burn::prelude::Device;
use posecoach_core::int8::{self, Requant};
use posecoach_core::weights::{
    self, Architecture, Dense, Header, Scales, Table, Tensors, Training, VERSION,
};
use rand::seq::IndexedRandom;

/// The activations' magnitudes of `model` on `windows` random golf windows of `pool`'s training
/// clips (real and synthetic swings and putts), each onto a random body in a random format,
/// in batches of `batch`.
///
/// # Errors
/// [`Error::NoClips`] without golf clips long enough, [`Error::Checkpoint`] if an activation
/// could not be read, else as [`Batch::new`].
pub fn calibrate(
    model: &Teacher,
    pool: &Pool,
    windows: usize,
    batch: usize,
    seed: u64,
    device: &Device,
) -> Result<Calibration, Error> {
    let golf = Pool {
        train: pool
            .train
            .iter()
            .filter(|c| c.has_club())
            .cloned()
            .collect(),
        ..Pool::default()
    };
    let mut rng = SplitRng::new(Split::Train, seed);
    let mut calibration = Calibration::default();
    while calibration.windows < windows {
        let n = batch.min(windows - calibration.windows).max(1);
        let mut sources: Vec<Window> = Vec::with_capacity(n);
        let mut targets = Vec::with_capacity(n);
        for _ in 0..n {
            let structure = *[Structure::Intra, Structure::Cross]
                .choose(rng.rng())
                .unwrap_or(&Structure::Cross);
            let example = golf.sample_example(&mut rng, structure, &Variation::FULL)?;
            sources.push(example.window);
            targets.push(example.target);
        }
        let onto: Vec<_> = targets.iter().collect();
        let batch = Batch::new(&sources, &onto, device)?;
        model.forward_observed(&batch, Some(&mut calibration));
        calibration.windows += n;
    }
    if calibration.unreadable {
        return Err(Error::Checkpoint(
            "calibration: an activation could not be read as f32".into(),
        ));
    }
    Ok(calibration)
}

/// A quantized layer's arrays.
struct Quantized {
    weights: Vec<i8>,
    bias: Vec<i32>,
    scale: Vec<f32>,
    requant: Vec<Requant>,
}

impl Quantized {
    fn tensors(&self) -> Tensors<'_> {
        Tensors {
            weights: &self.weights,
            bias: &self.bias,
            scale: &self.scale,
            requant: &self.requant,
        }
    }
}

/// Where a layer's inputs and outputs stand.
struct Units<'a> {
    /// The int8 scale of input `i` (1 for `f32` inputs).
    input: &'a dyn Fn(usize) -> f32,
    /// The int8 scale of the output, or `None` for an `f32` output.
    output: Option<f32>,
    /// Real values added to the bias, one row of outputs each; empty for one row, the bias.
    rows: &'a [f32],
}

/// `layer` quantized: weights folded with their inputs' scales, then per output channel.
///
/// # Errors
/// [`Error::Checkpoint`] if a requantization is out of [`Requant`]'s range or a bias beyond
/// [`weights::MAX_BIAS`] accumulator units (a non-finite one: every channel's unit holds its
/// biases within half that).
fn quantize(layer: &Layer, units: &Units<'_>) -> Result<Quantized, Error> {
    let n = layer.outputs();
    let mut out = Quantized {
        weights: Vec::with_capacity(layer.weight.len()),
        bias: Vec::new(),
        scale: Vec::with_capacity(n),
        requant: Vec::with_capacity(n),
    };
    let zeros = vec![0.0; n];
    let rows = match units.rows.is_empty() {
        true => &zeros[..],
        false => units.rows,
    };
    // Each channel's largest bias (over its rows), which its accumulator unit must hold
    // within half the core's bias range.
    let mut biggest = vec![0.0f32; n];
    for row in rows.chunks_exact(n) {
        for ((m, b), extra) in biggest.iter_mut().zip(&layer.bias).zip(row) {
            *m = m.max((b + extra).abs());
        }
    }
    let floor = |c: usize| biggest[c] / (weights::MAX_BIAS / 2) as f32;
    for (c, row) in layer.weight.chunks_exact(layer.inputs).enumerate() {
        let folded: Vec<f32> = row
            .iter()
            .enumerate()
            .map(|(i, w)| w * (units.input)(i))
            .collect();
        let largest = folded.iter().fold(TINY, |m, w| m.max(w.abs()));
        // A dead channel (zero weights) takes its unit from its bias instead.
        let scale = (largest / int8::MAX as f32).max(floor(c));
        out.weights
            .extend(folded.iter().map(|&w| int8::quantize(w, scale)));
        out.scale.push(scale);
        let factor = units.output.map_or(1.0, |s| scale / s);
        out.requant.push(Requant::new(factor).ok_or_else(|| {
            Error::Checkpoint(format!("requantization by {factor} out of range"))
        })?);
    }
    for row in rows.chunks_exact(n) {
        for ((b, extra), scale) in layer.bias.iter().zip(row).zip(&out.scale) {
            let units = ((b + extra) / scale).round();
            if units.is_nan() || units.abs() > weights::MAX_BIAS as f32 {
                return Err(Error::Checkpoint(format!(
                    "bias {} is {units} accumulator units, beyond the core's {}",
                    b + extra,
                    weights::MAX_BIAS
                )));
            }
            out.bias.push(units as i32);
        }
    }
    Ok(out)
}

/// `layer` with zero columns appended up to `inputs`.
fn padded(layer: Layer, inputs: usize) -> Layer {
    let weight = layer
        .weight
        .chunks_exact(layer.inputs)
        .flat_map(|row| {
            row.iter()
                .copied()
                .chain(std::iter::repeat_n(0.0, inputs - row.len()))
        })
        .collect();
    Layer {
        weight,
        inputs,
        ..layer
    }
}

/// `x · Wᵀ + b` for each row of `x`.
fn apply(layer: &Layer, x: &[f32]) -> Vec<f32> {
    x.chunks_exact(layer.inputs)
        .flat_map(|x| {
            layer
                .weight
                .chunks_exact(layer.inputs)
                .zip(&layer.bias)
                .map(|(row, b)| b + row.iter().zip(x).map(|(w, v)| w * v).sum::<f32>())
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The weights blob of `model` (sizes `config`) with activation `scales`.
///
/// # Errors
/// [`Error::Checkpoint`] for sizes or a prior the core cannot run (it corrects the chords:
/// [`PriorKind::Chords`]) or a scale out of range.
pub fn export(
    model: &Teacher,
    config: &TeacherConfig,
    scales: &Scales,
    training: Training,
) -> Result<Vec<u8>, Error> {
    let architecture = Architecture {
        features: config.features as u16,
        heads: config.heads as u16,
        kernel: config.kernel as u16,
        window: WINDOW as u16,
        segments: SEGMENTS as u16,
        rate_hz: RATE_HZ,
    };
    if config.prior != PriorKind::Chords {
        return Err(Error::Checkpoint(
            "the core's network corrects the chords (the analytic retargeter); this one \
             corrects the rotation transfer: distill it (`posecoach distill`) first"
                .into(),
        ));
    }
    if !architecture.is_supported() {
        return Err(Error::Checkpoint(format!(
            "sizes {config:?} are not what the core runs (at most {} features)",
            weights::MAX_FEATURES
        )));
    }
    let p: Parameters = model.parameters();
    let d = config.features;
    let s = scales;
    let one = |_: usize| 1.0;
    let motion = |i: usize| s.motion.get(i).copied().unwrap_or(1.0);
    let of = |v: f32| move |_: usize| v;
    let (hidden, joints, context, segments) =
        (of(s.hidden), of(s.joints), of(s.context), of(s.segments));
    let (down_1, fused, up_1, up_2, decoder) = (
        of(s.down_1),
        of(s.fused),
        of(s.up_1),
        of(s.up_2),
        of(s.decoder),
    );
    let rest = |l: &Layer, range| Layer {
        bias: vec![0.0; l.outputs()],
        ..l.columns(range)
    };
    let [query, key, value, output] = &p.attention;
    let [d1, d2, u1, u2] = &p.convolutions;
    let m = MOTION_CHANNELS;
    let layers: Vec<(Layer, Units<'_>)> = vec![
        (
            p.skeleton[0].clone(),
            Units {
                input: &one,
                output: None,
                rows: &[],
            },
        ),
        (
            p.skeleton[1].clone(),
            Units {
                input: &one,
                output: None,
                rows: &[],
            },
        ),
        (
            p.skeleton[2].clone(),
            Units {
                input: &one,
                output: None,
                rows: &[],
            },
        ),
        (
            padded(p.motion[0].columns(0..m), weights::MOTION_INPUTS),
            Units {
                input: &motion,
                output: Some(s.hidden),
                rows: &[],
            },
        ),
        (
            rest(&p.motion[0], m..m + REST_CHANNELS),
            Units {
                input: &one,
                output: None,
                rows: &[],
            },
        ),
        (
            p.motion[1].clone(),
            Units {
                input: &hidden,
                output: Some(s.joints),
                rows: &p.time,
            },
        ),
        (
            value.clone(),
            Units {
                input: &joints,
                output: None,
                rows: &[],
            },
        ),
        (
            output.clone(),
            Units {
                input: &context,
                output: Some(s.segments),
                rows: &p.tokens,
            },
        ),
        (
            d1.clone(),
            Units {
                input: &segments,
                output: Some(s.down_1),
                rows: &[],
            },
        ),
        (
            d2.clone(),
            Units {
                input: &down_1,
                output: Some(s.down_2),
                rows: &[],
            },
        ),
        (
            u1.clone(),
            Units {
                input: &fused,
                output: Some(s.up_1),
                rows: &[],
            },
        ),
        (
            u2.clone(),
            Units {
                input: &up_1,
                output: Some(s.up_2),
                rows: &[],
            },
        ),
        (
            p.decoder[0].columns(0..d),
            Units {
                input: &up_2,
                output: Some(s.decoder),
                rows: &[],
            },
        ),
        (
            rest(&p.decoder[0], d..d + REST_CHANNELS),
            Units {
                input: &one,
                output: None,
                rows: &[],
            },
        ),
        (
            p.decoder[1].clone(),
            Units {
                input: &decoder,
                output: None,
                rows: &[],
            },
        ),
        (
            p.root.clone(),
            Units {
                input: &up_2,
                output: None,
                rows: &[],
            },
        ),
    ];
    let quantized = layers
        .iter()
        .map(|(layer, units)| quantize(layer, units))
        .collect::<Result<Vec<_>, _>>()?;
    let tensors: Vec<Tensors<'_>> = quantized.iter().map(Quantized::tensors).collect();
    let tensors: [Tensors<'_>; Dense::ALL.len()] = tensors
        .try_into()
        .map_err(|_| Error::Checkpoint("layer count".into()))?;
    let heads = p.heads;
    let width = d / heads;
    let root = (width as f32).sqrt();
    let queries = apply(query, &p.tokens);
    let token_keys = apply(key, &p.tokens);
    let values = apply(value, &p.tokens);
    let (mut joint_logits, mut offsets, mut token_logits) = (Vec::new(), Vec::new(), Vec::new());
    for (q, k) in queries.chunks_exact(d).zip(token_keys.chunks_exact(d)) {
        for h in 0..heads {
            let span = h * width..(h + 1) * width;
            let through = |c: usize| q[c] / root;
            joint_logits.extend((0..d).map(|i| {
                span.clone()
                    .map(|c| through(c) * key.weight[c * d + i])
                    .sum::<f32>()
                    * s.joints
            }));
            offsets.push(span.clone().map(|c| through(c) * key.bias[c]).sum::<f32>());
            token_logits.push(span.clone().map(|c| through(c) * k[c]).sum::<f32>());
        }
    }
    let tables: [&[f32]; Table::ALL.len()] = [&joint_logits, &offsets, &token_logits, &values];
    let header = Header {
        version: VERSION,
        architecture,
        scales: *scales,
        training,
    };
    let mut out = vec![0u8; weights::max_len(&architecture)];
    let len = weights::write(&header, &tensors, &tables, &mut out)
        .map_err(|e| Error::Checkpoint(e.to_string()))?;
    out.truncate(len);
    Ok(out)
}

/// The formats characters are drawn in, for [`Training::formats`].
pub fn trained_formats() -> heapless::Vec<posecoach_core::format::Format, { weights::MAX_FORMATS }>
{
    FORMATS.iter().copied().take(weights::MAX_FORMATS).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::pair_on;
    use crate::infer::Retargeter;
    use crate::train::load_teacher;
    use std::path::PathBuf;

    #[test]
    fn quantized_layers_hold_their_weights_to_half_a_step() {
        let layer = Layer {
            weight: vec![0.5, -0.25, 0.1, 0.0, 0.0, 0.0],
            bias: vec![0.3, -0.2],
            inputs: 3,
        };
        let input = |i: usize| [0.01, 0.02, 0.04][i];
        let rows = [1.0, 2.0, 3.0, 4.0];
        let q = quantize(
            &layer,
            &Units {
                input: &input,
                output: Some(0.05),
                rows: &rows,
            },
        )
        .unwrap();
        // Row 0 folded: 0.005, -0.005, 0.004; its scale 0.005 / 127.
        let scale = 0.005 / 127.0;
        assert!((q.scale[0] - scale).abs() < 1e-9);
        assert_eq!(&q.weights[..3], &[127, -127, 102]);
        // A zero row keeps a valid scale and zero weights.
        assert_eq!(&q.weights[3..], &[0, 0, 0]);
        assert!(q.scale[1] > 0.0);
        // One bias row per extra row: (b + extra) in accumulator units.
        assert_eq!(q.bias.len(), 4);
        assert_eq!(q.bias[0], ((0.3 + 1.0) / q.scale[0]).round() as i32);
        assert_eq!(q.bias[3], ((-0.2 + 4.0) / q.scale[1]).round() as i32);
        assert!((q.requant[0].factor() - scale / 0.05).abs() < 1e-9);
    }

    /// The committed distilled network, quantized with scales from synthetic swings, follows
    /// the float one closely on a golf swing onto another body and format.
    #[test]
    fn the_int8_distilled_network_follows_the_float_one() {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../weights/distilled.pcw");
        let device = Device::flex();
        let (model, config, _) = load_teacher(&path, &device).unwrap();
        let mut pool = Pool::default();
        pool.add_synthetic_golf(4, 1).unwrap();
        let calibration = calibrate(&model, &pool, 64, 16, 2, &device).unwrap();
        assert_eq!(calibration.windows, 64);
        let training = Training {
            name: "test".try_into().unwrap(),
            steps: 0,
            seed: 0,
            calibration_windows: 64,
            formats: trained_formats(),
        };
        let bytes = export(&model, &config.teacher, &calibration.scales(), training).unwrap();
        let int8 = Retargeter::int8("int8".into(), &bytes).unwrap();
        let float = Retargeter::load(&path).unwrap();
        let mut rng = SplitRng::new(Split::Eval, 3);
        let clip = &pool.eval[0];
        let pair = pair_on(clip, &mut rng, Structure::Cross, &Variation::STANDARD_REST).unwrap();
        let h = pair.target.skeleton.height();
        let a = int8.retarget(&pair.source, &pair.target.skeleton).unwrap();
        let b = float.retarget(&pair.source, &pair.target.skeleton).unwrap();
        let analytic = crate::metrics::Baseline::Analytic.retarget(&pair).unwrap();
        let mean = |x: &[posecoach_core::Vec3], y: &[posecoach_core::Vec3]| {
            x.iter().zip(y).map(|(p, q)| (p - q).norm()).sum::<f32>() / x.len() as f32 / h
        };
        let (gap, correction) = (
            mean(&a.positions, &b.positions),
            mean(&b.positions, &analytic.positions),
        );
        assert!(gap < 0.002, "{gap}");
        assert!(gap < 0.25 * correction, "{gap} against {correction}");
    }
}
