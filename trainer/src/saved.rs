//! A trained int8 model as a file (`model.json` in `trainer train --out`): everything the integer
//! reference path needs, so `trainer eval --model DIR` scores a model without exporting it into the
//! source tree and rebuilding. The compiled-in form stays `weights.rs` (crate::quant::generate).
use crate::error::{Error, Result};
use crate::export::{SPLIT_LINE, provenance_data, provenance_manifest};
use crate::features::parse_feature;
use crate::model::FloatLayer;
use crate::prep::{Angle, Prep};
use crate::quant::{QCascade, QLayer};
use estimator_core::normalize::{Envelope, Norm, TURBULENCE_BANDS, TurbulenceEnvelope};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Format of `model.json`; a file of another format is refused by number.
pub const FORMAT: u32 = 1;

#[derive(Serialize, Deserialize)]
struct Layer {
    weights: Vec<Vec<i8>>,
    bias: Vec<i32>,
    requant: Vec<(i32, u8, i32)>,
    hidden: bool,
}

#[derive(Serialize, Deserialize)]
struct Cascade {
    angle: Angle,
    features: Vec<String>,
    /// `(center, mult, shift)` per input.
    norm: Vec<(i32, i32, u8)>,
    envelope: Vec<(i32, i32)>,
    mid_norm: (i32, i32, u8),
    out_center: i32,
    out_sigma: f64,
    out_range: (i32, i32),
    turbulence_speed_lo_mms: i32,
    turbulence_band_mms: i32,
    turbulence_limit_urad: Vec<i32>,
    lift_scale: (i32, i32),
    part1: Vec<Layer>,
    part2: Vec<Layer>,
    /// The float parts the int8 ones were quantized from (what `trainer finetune` trains further);
    /// absent from a model.json written before they were saved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    float: Option<FloatParts>,
}

/// A cascade's float parts, `[part1, part2]`.
#[derive(Serialize, Deserialize, Clone)]
struct FloatParts {
    part1: Vec<FloatLayer>,
    part2: Vec<FloatLayer>,
}

/// The float parts of a saved cascade and its int8 form (whose scaling they keep).
pub struct FloatCascade {
    pub part1: Vec<FloatLayer>,
    pub part2: Vec<FloatLayer>,
    pub q: QCascade,
}

/// The saved model: both cascades, the sensor suite they read and the training provenance.
#[derive(Serialize, Deserialize)]
pub struct SavedModel {
    pub format: u32,
    pub suite: String,
    pub provenance: String,
    alpha: Cascade,
    beta: Cascade,
}

fn norm(n: &Norm) -> (i32, i32, u8) {
    (n.center, n.mult, n.shift)
}

fn unnorm((center, mult, shift): (i32, i32, u8)) -> Norm {
    Norm {
        center,
        mult,
        shift,
    }
}

fn layers(ls: &[QLayer]) -> Vec<Layer> {
    ls.iter()
        .map(|l| Layer {
            weights: l.weights.clone(),
            bias: l.bias.clone(),
            requant: l.requant.clone(),
            hidden: l.hidden,
        })
        .collect()
}

fn unlayers(ls: Vec<Layer>) -> Vec<QLayer> {
    ls.into_iter()
        .map(|l| QLayer {
            weights: l.weights,
            bias: l.bias,
            requant: l.requant,
            hidden: l.hidden,
        })
        .collect()
}

impl Cascade {
    fn of(q: &QCascade, float: Option<(&[FloatLayer], &[FloatLayer])>) -> Cascade {
        let p = &q.prep;
        Cascade {
            angle: p.angle,
            features: p.features.iter().map(|f| f.name().to_string()).collect(),
            norm: p.norm.iter().map(norm).collect(),
            envelope: p.envelope.iter().map(|e| (e.lo, e.hi)).collect(),
            mid_norm: norm(&p.mid_norm),
            out_center: p.out_center,
            out_sigma: p.out_sigma,
            out_range: (p.out_range.lo, p.out_range.hi),
            turbulence_speed_lo_mms: p.turbulence.speed_lo_mms,
            turbulence_band_mms: p.turbulence.band_mms,
            turbulence_limit_urad: p.turbulence.limit_urad.to_vec(),
            lift_scale: (p.lift_scale.lo, p.lift_scale.hi),
            part1: layers(&q.part1),
            part2: layers(&q.part2),
            float: float.map(|(part1, part2)| FloatParts {
                part1: part1.to_vec(),
                part2: part2.to_vec(),
            }),
        }
    }

    fn into_q(self, path: &Path) -> Result<QCascade> {
        let bad = |msg: String| Error::Model {
            path: path.to_path_buf(),
            msg,
        };
        let n = self.features.len();
        if self.norm.len() != n || self.envelope.len() != n {
            return Err(bad(format!(
                "{} features but {} normalisations and {} envelopes",
                n,
                self.norm.len(),
                self.envelope.len()
            )));
        }
        let limit_urad: [i32; TURBULENCE_BANDS] =
            self.turbulence_limit_urad
                .try_into()
                .map_err(|v: Vec<i32>| {
                    bad(format!(
                        "{} turbulence bands, this build has {TURBULENCE_BANDS}",
                        v.len()
                    ))
                })?;
        let features = self
            .features
            .iter()
            .map(|f| parse_feature(f))
            .collect::<Result<Vec<_>>>()?;
        let (part1, part2) = (unlayers(self.part1), unlayers(self.part2));
        // The shapes must chain: part 1 reads the features, every layer the previous one's outputs.
        for part in [&part1, &part2] {
            let mut width = None;
            for l in part.iter() {
                if l.bias.len() != l.n_out() || l.requant.len() != l.n_out() {
                    return Err(bad(
                        "a layer's bias or requantization does not match its outputs".into(),
                    ));
                }
                if let Some(w) = width
                    && w != l.n_in()
                {
                    return Err(bad(format!(
                        "a layer reads {} inputs after a layer of {w}",
                        l.n_in()
                    )));
                }
                width = Some(l.n_out());
            }
        }
        if part1.first().map(|l| l.n_in()) != Some(n) {
            return Err(bad(format!("part 1 does not read the {n} features")));
        }
        Ok(QCascade {
            prep: Prep {
                angle: self.angle,
                features,
                norm: self.norm.into_iter().map(unnorm).collect(),
                envelope: self
                    .envelope
                    .into_iter()
                    .map(|(lo, hi)| Envelope { lo, hi })
                    .collect(),
                mid_norm: unnorm(self.mid_norm),
                out_center: self.out_center,
                out_sigma: self.out_sigma,
                out_range: Envelope {
                    lo: self.out_range.0,
                    hi: self.out_range.1,
                },
                turbulence: TurbulenceEnvelope {
                    speed_lo_mms: self.turbulence_speed_lo_mms,
                    band_mms: self.turbulence_band_mms,
                    limit_urad,
                },
                lift_scale: Envelope {
                    lo: self.lift_scale.0,
                    hi: self.lift_scale.1,
                },
            },
            part1,
            part2,
        })
    }
}

/// The float parts of a cascade in `path`, checked to have the shapes of its int8 parts.
fn float_parts(c: &Cascade, path: &Path) -> Result<FloatParts> {
    let bad = |msg: String| Error::Model {
        path: path.to_path_buf(),
        msg,
    };
    let f = c.float.clone().ok_or_else(|| {
        bad(format!(
            "the {} cascade has no float weights (the model was saved before they were): retrain it with this build's `trainer train`",
            c.angle.name()
        ))
    })?;
    for (float, int) in [(&f.part1, &c.part1), (&f.part2, &c.part2)] {
        let same = float.len() == int.len()
            && float.iter().zip(int).all(|(fl, il)| {
                fl.bias.len() == il.bias.len()
                    && fl.weights.len() == il.weights.len()
                    && fl
                        .weights
                        .iter()
                        .zip(&il.weights)
                        .all(|(a, b)| a.len() == b.len())
            });
        if !same {
            return Err(bad(format!(
                "the {} cascade's float weights do not have its int8 layers' shapes",
                c.angle.name()
            )));
        }
    }
    Ok(f)
}

impl SavedModel {
    /// The saved form of two quantized cascades (α, β), with the float parts they were quantized
    /// from where given (`[α, β]`, each `(part1, part2)`).
    pub fn new(
        alpha: &QCascade,
        beta: &QCascade,
        float: Option<[(&[FloatLayer], &[FloatLayer]); 2]>,
        suite: &str,
        provenance: &str,
    ) -> SavedModel {
        let [fa, fb] = match float {
            Some([a, b]) => [Some(a), Some(b)],
            None => [None, None],
        };
        SavedModel {
            format: FORMAT,
            suite: suite.to_string(),
            provenance: provenance.to_string(),
            alpha: Cascade::of(alpha, fa),
            beta: Cascade::of(beta, fb),
        }
    }

    /// Writes `dir/model.json`.
    pub fn write(&self, dir: &Path) -> Result<std::path::PathBuf> {
        let path = dir.join("model.json");
        let text = serde_json::to_string(self).map_err(|e| Error::Model {
            path: path.clone(),
            msg: e.to_string(),
        })?;
        std::fs::write(&path, text).map_err(|source| Error::Io {
            action: "write",
            path: path.clone(),
            source,
        })?;
        Ok(path)
    }

    /// Reads `dir/model.json` into the two cascades (α, β), the suite name and the provenance.
    pub fn read(dir: &Path) -> Result<(QCascade, QCascade, String, String)> {
        let (m, path) = SavedModel::parse(dir)?;
        let alpha = m.alpha.into_q(&path)?;
        let beta = m.beta.into_q(&path)?;
        Ok((alpha, beta, m.suite, m.provenance))
    }

    /// Reads `dir/model.json` with its float parts (refused where it has none): `[α, β]`, the
    /// suite name and the provenance.
    pub fn read_float(dir: &Path) -> Result<([FloatCascade; 2], String, String)> {
        let (m, path) = SavedModel::parse(dir)?;
        let (fa, fb) = (float_parts(&m.alpha, &path)?, float_parts(&m.beta, &path)?);
        let cascade = |f: FloatParts, q: QCascade| FloatCascade {
            part1: f.part1,
            part2: f.part2,
            q,
        };
        Ok((
            [
                cascade(fa, m.alpha.into_q(&path)?),
                cascade(fb, m.beta.into_q(&path)?),
            ],
            m.suite,
            m.provenance,
        ))
    }

    /// One model of the α cascade of the model in `alpha_dir` and the β cascade of the one in
    /// `beta_dir` (`trainer combine`): the two networks are trained apart and read nothing of each
    /// other, so either can come from another training. Both must read the same sensor suite and
    /// have trained on the same dataset (their provenances' first line, which `trainer export`
    /// checks against its `--data`); the provenance keeps both trainings'.
    pub fn combine(alpha_dir: &Path, beta_dir: &Path) -> Result<SavedModel> {
        let (a, a_path) = SavedModel::parse(alpha_dir)?;
        let (b, b_path) = SavedModel::parse(beta_dir)?;
        let refuse = |msg: String| Error::Model {
            path: b_path.clone(),
            msg,
        };
        if a.suite != b.suite {
            return Err(refuse(format!(
                "reads the sensor suite {}, the α model ({}) {}: combine models of one suite",
                b.suite,
                a_path.display(),
                a.suite
            )));
        }
        // The first line names the training dataset by its manifest (`trainer export` checks that
        // part against its --data); the path before it may be written either way.
        let first = |p: &str| p.lines().next().unwrap_or("").to_string();
        let dataset = first(&a.provenance);
        let Some(manifest) = provenance_manifest(&a.provenance) else {
            return Err(Error::Model {
                path: a_path.clone(),
                msg: format!(
                    "its provenance names no training dataset's manifest (its first line is `{dataset}`): give --alpha a model written by `trainer train --out`"
                ),
            });
        };
        if provenance_manifest(&b.provenance) != Some(manifest) {
            return Err(refuse(format!(
                "was trained on `{}`, the α model ({}) on `{dataset}`: combine models trained with the same --data",
                first(&b.provenance),
                a_path.display()
            )));
        }
        // The data lines (what `provenance_data` gives a report) name both networks' training
        // data; the split line ends them; each training's provenance follows whole. It ends as a
        // training's does, with a newline (`trainer finetune` appends to it).
        let provenance = format!(
            "{dataset}\ncombined (trainer combine): the α network of {}, trained on {}; the β network of {}, trained on {}\n{SPLIT_LINE} each network's own, below\nthe α network's training:\n{}\nthe β network's training:\n{}\n",
            alpha_dir.display(),
            provenance_data(&a.provenance),
            beta_dir.display(),
            provenance_data(&b.provenance),
            a.provenance.trim_end(),
            b.provenance.trim_end()
        );
        Ok(SavedModel {
            format: FORMAT,
            suite: a.suite,
            provenance,
            alpha: a.alpha,
            beta: b.beta,
        })
    }

    /// `dir/model.json`, its format and the order of its cascades checked.
    fn parse(dir: &Path) -> Result<(SavedModel, std::path::PathBuf)> {
        let path = dir.join("model.json");
        let text = std::fs::read_to_string(&path).map_err(|source| Error::Io {
            action: "read",
            path: path.clone(),
            source,
        })?;
        let m: SavedModel = serde_json::from_str(&text).map_err(|e| Error::Model {
            path: path.clone(),
            msg: format!("{e} (write it with `trainer train --out DIR`)"),
        })?;
        if m.format != FORMAT {
            return Err(Error::Model {
                path,
                msg: format!(
                    "format {}, this build reads format {FORMAT} (retrain with this build's `trainer train`)",
                    m.format
                ),
            });
        }
        if m.alpha.angle != Angle::Alpha || m.beta.angle != Angle::Beta {
            return Err(Error::Model {
                path,
                msg: "the cascades are not α then β".into(),
            });
        }
        Ok((m, path))
    }
}

/// The networks and provenance of a `weights.rs` that [`crate::quant::generate`] wrote (the
/// compiled-in `estimator-core/src/model/NAME/weights.rs`): what `trainer revector --weights`
/// remakes the test vectors from when the networks' `model.json` is gone, e.g. after a change of
/// the air-data filter whose features the vectors carry. Read back exactly: the networks and
/// provenance found must generate the file byte for byte again, or the file is refused (edited by
/// hand, or written by another version). The float parts, the output centre and σ are not in the
/// file and are not needed by the integer reference.
pub fn read_generated(path: &Path) -> Result<(QCascade, QCascade, String)> {
    let refuse = |msg: String| Error::Model {
        path: path.to_path_buf(),
        msg,
    };
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        action: "read",
        path: path.to_path_buf(),
        source,
    })?;
    let alpha = generated_cascade(&text, "ALPHA", Angle::Alpha).map_err(refuse)?;
    let beta = generated_cascade(&text, "BETA", Angle::Beta).map_err(refuse)?;
    let prov = between(&text, "pub const PROVENANCE: &str = ", ";\n")
        .and_then(unquote)
        .ok_or_else(|| refuse("holds no PROVENANCE string".into()))?;
    if crate::quant::generate(&alpha, &beta, &prov) != text {
        return Err(refuse(format!(
            "is not a weights.rs this trainer writes for the {} (read back, it does not generate the same file): export the model again from its model.json, or give a file `trainer train --export` wrote",
            estimator_core::aircraft::AIRCRAFT.name
        )));
    }
    Ok((alpha, beta, prov))
}

/// The text between the first `start` and the next `end` after it.
fn between<'a>(text: &'a str, start: &str, end: &str) -> Option<&'a str> {
    let (_, rest) = text.split_once(start)?;
    rest.split_once(end).map(|(mid, _)| mid)
}

/// A Rust string literal as `{:?}` writes it.
fn unquote(lit: &str) -> Option<String> {
    let inner = lit.strip_prefix('"')?.strip_suffix('"')?;
    let mut out = String::new();
    let mut chars = inner.chars();
    while let Some(c) = chars.next() {
        if c != '\\' {
            out.push(c);
            continue;
        }
        match chars.next()? {
            'n' => out.push('\n'),
            't' => out.push('\t'),
            'r' => out.push('\r'),
            '0' => out.push('\0'),
            e @ ('\\' | '"' | '\'') => out.push(e),
            'u' => {
                let hex: String = chars.by_ref().skip(1).take_while(|c| *c != '}').collect();
                out.push(char::from_u32(u32::from_str_radix(&hex, 16).ok()?)?);
            }
            _ => return None,
        }
    }
    Some(out)
}

/// The integers of `s` in order (decimal, with a sign), whatever stands between them.
fn integers(s: &str) -> std::result::Result<Vec<i64>, String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    for c in s.chars().chain(std::iter::once(' ')) {
        if c.is_ascii_digit() || (c == '-' && cur.is_empty()) {
            cur.push(c);
        } else if !cur.is_empty() {
            if cur != "-" {
                out.push(cur.parse::<i64>().map_err(|e| format!("`{cur}`: {e}"))?);
            }
            cur.clear();
        }
    }
    Ok(out)
}

fn int<T: TryFrom<i64>>(v: i64) -> std::result::Result<T, String> {
    T::try_from(v).map_err(|_| format!("{v} is out of range"))
}

/// `Norm { center, mult, shift }` and `Envelope { lo, hi }` items, one per line.
fn norms(s: &str) -> std::result::Result<Vec<Norm>, String> {
    s.lines()
        .filter(|l| !l.trim().is_empty())
        .map(
            |l| match integers(l.split_once('{').map_or("", |(_, r)| r))?[..] {
                [c, m, sh] => Ok(Norm {
                    center: int(c)?,
                    mult: int(m)?,
                    shift: int(sh)?,
                }),
                _ => Err(format!("`{l}` is not a Norm")),
            },
        )
        .collect()
}

fn envelope(s: &str) -> std::result::Result<Envelope, String> {
    match integers(s.split_once('{').map_or("", |(_, r)| r))?[..] {
        [lo, hi] => Ok(Envelope {
            lo: int(lo)?,
            hi: int(hi)?,
        }),
        _ => Err(format!("`{s}` is not an Envelope")),
    }
}

/// The `Dense::new(weights, bias, requant)` layers of a part, in order; the last is the output.
fn dense_layers(s: &str) -> std::result::Result<Vec<QLayer>, String> {
    let blocks: Vec<&str> = s.split("crate::nn::Dense::new(\n").skip(1).collect();
    let n = blocks.len();
    blocks
        .iter()
        .enumerate()
        .map(|(i, b)| {
            // `[` rows (`[w,…],` a line each) `],` `[` bias `],` `[` requantizations `],` `)`.
            let (w, rest) = b
                .split_once("],\n],\n[")
                .ok_or("a Dense::new without its weight rows".to_string())?;
            let (bias, rq) = rest
                .split_once("],\n[")
                .ok_or("a Dense::new without bias and requantization".to_string())?;
            let weights = w
                .lines()
                .map(|row| integers(row)?.into_iter().map(int::<i8>).collect())
                .collect::<std::result::Result<Vec<Vec<i8>>, String>>()?;
            let bias = integers(bias)?
                .into_iter()
                .map(int::<i32>)
                .collect::<std::result::Result<_, _>>()?;
            let requant = integers(rq.split("],\n)").next().unwrap_or(""))?
                .chunks(3)
                .map(|c| match *c {
                    [m, sh, o] => Ok((int(m)?, int(sh)?, int(o)?)),
                    _ => Err("a Requant without mult, shift and offset".to_string()),
                })
                .collect::<std::result::Result<_, _>>()?;
            Ok(QLayer {
                weights,
                bias,
                requant,
                hidden: i + 1 < n,
            })
        })
        .collect()
}

/// One `pub static NAME: crate::CascadeNet<…> = crate::CascadeNet { … };` item.
fn generated_cascade(
    text: &str,
    name: &str,
    angle: Angle,
) -> std::result::Result<QCascade, String> {
    let item = between(
        text,
        &format!("pub static {name}: crate::CascadeNet<"),
        "\n};\n",
    )
    .ok_or(format!("holds no {name} cascade"))?;
    // Every field then ends in ",\n", the last one too.
    let item = &format!("{item}\n");
    let field =
        |start: &str, end: &str| between(item, start, end).ok_or(format!("{name}: no `{start}`"));
    let known: std::collections::HashMap<String, estimator_core::Feature> =
        estimator_core::Feature::ALL
            .iter()
            .map(|f| (crate::quant::feature_path(*f), *f))
            .collect();
    // Each feature's path ends in ", " (`static_item`); paths hold ", " themselves, so the list
    // is read as the longest known path at each point.
    let mut rest = field("features: [", "],\nnorm: [")?;
    let mut features = Vec::new();
    while !rest.trim().is_empty() {
        rest = rest.trim_start();
        let (path, f) = known
            .iter()
            .filter(|(p, _)| {
                rest.strip_prefix(p.as_str())
                    .is_some_and(|r| r.starts_with(", "))
            })
            .max_by_key(|(p, _)| p.len())
            .ok_or(format!(
                "{name}: unknown feature at `{}`",
                rest.chars().take(60).collect::<String>()
            ))?;
        features.push(*f);
        rest = rest.get(path.len() + 2..).unwrap_or("");
    }
    let turbulence = match integers(field(
        "turbulence: crate::normalize::TurbulenceEnvelope {",
        "},\n",
    )?)?[..]
    {
        [lo, band, ref limits @ ..] if limits.len() == TURBULENCE_BANDS => TurbulenceEnvelope {
            speed_lo_mms: int(lo)?,
            band_mms: int(band)?,
            limit_urad: std::array::from_fn(|i| limits.get(i).map_or(0, |v| *v as i32)),
        },
        _ => {
            return Err(format!(
                "{name}: the turbulence envelope is not {TURBULENCE_BANDS} bands"
            ));
        }
    };
    let prep = Prep {
        angle,
        features,
        norm: norms(field("norm: [\n", "],\nenvelope: [")?)?,
        envelope: field("envelope: [\n", "],\npart1: ")?
            .lines()
            .map(envelope)
            .collect::<std::result::Result<_, _>>()?,
        mid_norm: norms(field("mid_norm: ", ",\npart2: ")?)?
            .pop()
            .ok_or(format!("{name}: no mid_norm"))?,
        out_center: 0,
        out_sigma: 1.0,
        out_range: envelope(field("out_range: ", ",\n")?)?,
        turbulence,
        lift_scale: envelope(field("lift_scale: ", ",\n")?)?,
    };
    Ok(QCascade {
        prep,
        part1: dense_layers(field("part1: ", ",\nmid_norm: ")?)?,
        part2: dense_layers(field(",\npart2: ", ",\nout_range: ")?)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model.json in a new directory under the system's temp dir: cascades with no layers, each
    /// told apart by its `out_center` (α `centers.0`, β `centers.1`).
    fn saved(name: &str, suite: &str, provenance: &str, centers: (i32, i32)) -> std::path::PathBuf {
        let cascade = |angle: &str, center: i32| {
            serde_json::json!({
                "angle": angle, "features": [], "norm": [], "envelope": [], "mid_norm": [0, 1, 0],
                "out_center": center, "out_sigma": 1.0, "out_range": [-1, 1],
                "turbulence_speed_lo_mms": 0, "turbulence_band_mms": 1, "turbulence_limit_urad": [],
                "lift_scale": [0, 1], "part1": [], "part2": []
            })
        };
        let dir =
            std::env::temp_dir().join(format!("trainer-combine-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let m = serde_json::json!({
            "format": FORMAT, "suite": suite, "provenance": provenance,
            "alpha": cascade("Alpha", centers.0), "beta": cascade("Beta", centers.1)
        });
        std::fs::write(dir.join("model.json"), m.to_string()).unwrap();
        dir
    }

    /// The build's committed weights.rs and vectors, where it has a model.
    fn committed(file: &str) -> Option<std::path::PathBuf> {
        let name = estimator_core::aircraft::AIRCRAFT.name;
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let p = match file {
            "weights" => root.join(format!("estimator-core/src/model/{name}/weights.rs")),
            _ => root.join(format!("estimator-core/tests/vectors/{name}.txt")),
        };
        p.exists().then_some(p)
    }

    #[test]
    fn the_committed_weights_read_back_and_remake_their_vectors_bit_for_bit() {
        let (Some(w), Some(v)) = (committed("weights"), committed("vectors")) else {
            panic!("this build's aircraft has no committed weights and vectors");
        };
        let (alpha, beta, prov) = read_generated(&w).unwrap();
        assert_eq!(
            Some(prov.as_str()),
            estimator_core::model::SHIPPED_PROVENANCE
        );
        // The vectors' frames through this build's features and the networks read back give the
        // committed expected outputs: the file and the filter agree (after a filter change,
        // `trainer revector` remakes them).
        let old = crate::quant::parse_vectors(&std::fs::read_to_string(&v).unwrap()).unwrap();
        let frames: Vec<_> = old.iter().map(|x| (x.reset, x.frame)).collect();
        assert_eq!(crate::quant::vectors(&alpha, &beta, &frames), old);

        // One weight changed by hand: the file no longer generates itself, and is refused.
        let text = std::fs::read_to_string(&w).unwrap();
        let edited = text.replacen(
            "crate::nn::Dense::new(\n[[",
            "crate::nn::Dense::new(\n[[1",
            1,
        );
        assert_ne!(edited, text);
        let tmp = std::env::temp_dir().join(format!("trainer-weights-{}.rs", std::process::id()));
        std::fs::write(&tmp, edited).unwrap();
        match read_generated(&tmp) {
            Err(Error::Model { msg, .. }) => assert!(
                msg.contains("does not generate the same file") || msg.contains("out of range"),
                "{msg}"
            ),
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("an edited weights.rs was read"),
        }
        std::fs::remove_file(tmp).unwrap();
    }

    #[test]
    fn combine_takes_alpha_from_one_model_and_beta_from_the_other() {
        let sha = "ab".repeat(32);
        let data = &format!("dataset: out/data/large (preset large), manifest sha256 {sha}");
        let a = saved(
            "a",
            "egi120",
            &format!("{data}\nplus extra A\nsplit by flight: a\nseed: 1; a"),
            (11, 12),
        );
        let b = saved(
            "b",
            "egi120",
            &format!("{data}\nplus extra B\nsplit by flight: b\nseed: 1; b\n"),
            (21, 22),
        );
        let m = SavedModel::combine(&a, &b).unwrap();
        assert_eq!((m.alpha.out_center, m.beta.out_center), (11, 22));
        assert_eq!(m.suite, "egi120");
        // The first line stays the dataset's, which `trainer export` checks; both trainings follow.
        assert_eq!(m.provenance.lines().next(), Some(data.as_str()));
        assert!(m.provenance.contains("seed: 1; a") && m.provenance.contains("seed: 1; b"));
        // What a report names as the training data names both trainings' data and stops there.
        let summary = provenance_data(&m.provenance);
        assert!(
            summary.contains("plus extra A")
                && summary.contains("plus extra B")
                && !summary.contains("seed: 1"),
            "{summary}"
        );
        assert!(m.provenance.ends_with("seed: 1; b\n"));
        // The same dataset written as another path is the same dataset.
        let e = saved(
            "e",
            "egi120",
            &data.replace("out/data/large", "./out/data/large/"),
            (51, 52),
        );
        assert_eq!(SavedModel::combine(&a, &e).unwrap().beta.out_center, 52);
        // It reads back as a model.
        let out = a.join("combined");
        std::fs::create_dir_all(&out).unwrap();
        m.write(&out).unwrap();
        let (back, _) = SavedModel::parse(&out).unwrap();
        assert_eq!((back.alpha.out_center, back.beta.out_center), (11, 22));

        // Another suite, or another training dataset, is refused.
        let c = saved("c", "egi", &format!("{data}\nc"), (31, 32));
        let d = saved(
            "d",
            "egi120",
            &format!(
                "dataset: out/data/paper (preset paper), manifest sha256 {}",
                "cd".repeat(32)
            ),
            (41, 42),
        );
        for (other, why) in [(&c, "of one suite"), (&d, "with the same --data")] {
            match SavedModel::combine(&a, other) {
                Err(Error::Model { msg, .. }) => assert!(msg.contains(why), "{msg}"),
                Err(e) => panic!("{e}"),
                Ok(_) => panic!("combined {} with {}", a.display(), other.display()),
            }
        }
        // An α model whose provenance names no manifest is refused as the α model's fault.
        let f = saved("f", "egi120", "dataset: somewhere", (61, 62));
        match SavedModel::combine(&f, &a) {
            Err(Error::Model { path, msg }) => {
                assert!(path.starts_with(&f) && msg.contains("--alpha"), "{msg}")
            }
            other => panic!("{:?}", other.map(|m| m.provenance)),
        }
        for dir in [a, b, c, d, e, f] {
            std::fs::remove_dir_all(dir).unwrap();
        }
    }
}
