//! The table of metadata keys ([`KEYS`]): each key's name, writer and reader, in one row.

use super::metadata::{EstimateMethod, EstimateRecord, GuideRecord, RenderMetadata};
use crate::integrator::rrs::Roulette;
use crate::names::{parse_value, value_name};
use std::str::FromStr;

/// One metadata key: its name, its value written from the metadata (`None`: not written), and
/// its value (or its absence) read into metadata being built, in table order.
pub struct Key {
    pub name: &'static str,
    pub(super) write: fn(&RenderMetadata) -> Option<String>,
    pub(super) read: fn(&mut RenderMetadata, Value) -> std::result::Result<(), String>,
}

/// A key's text as an image holds it (`None`: the image lacks the key), read with errors that
/// name the key.
#[derive(Clone, Copy)]
pub(super) struct Value<'a> {
    pub(super) key: &'static str,
    pub(super) text: Option<&'a str>,
}

impl<'a> Value<'a> {
    /// The text of a key every vrpt render has.
    fn required(self) -> std::result::Result<&'a str, String> {
        self.text
            .ok_or_else(|| format!("no '{}' in its metadata: not a vrpt render", self.key))
    }

    fn number<T: FromStr>(self, text: &str) -> std::result::Result<T, String> {
        text.trim()
            .parse()
            .map_err(|_| format!("metadata '{}' is '{text}', not a valid number", self.key))
    }

    /// A number the key must have.
    fn num<T: FromStr>(self) -> std::result::Result<T, String> {
        self.number(self.required()?)
    }

    /// A number the key may have.
    fn opt<T: FromStr>(self) -> std::result::Result<Option<T>, String> {
        self.text.map(|t| self.number(t)).transpose()
    }

    /// A finite, non-negative number the key must have.
    fn non_negative(self) -> std::result::Result<f64, String> {
        let v: f64 = self.num()?;
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(format!(
                "metadata '{}' must be a finite non-negative number",
                self.key
            ))
        }
    }

    /// A finite number of seconds the key may have.
    fn seconds(self) -> std::result::Result<Option<f64>, String> {
        match self.opt::<f64>()? {
            Some(t) if !t.is_finite() || t < 0.0 => {
                Err(format!("metadata '{}' must be a finite time", self.key))
            }
            t => Ok(t),
        }
    }

    /// An axis value the key may have, by its command-line name.
    fn axis<T: clap::ValueEnum>(self, what: &str) -> std::result::Result<Option<T>, String> {
        self.text.map(|t| parse_value(t, what)).transpose()
    }
}

/// A number written with `to_string`.
fn text<T: ToString>(v: T) -> Option<String> {
    Some(v.to_string())
}

/// Seconds written to the microsecond.
fn micros(s: f64) -> Option<String> {
    Some(format!("{s:.6}"))
}

/// `*slot = value`, as a row's reader returns it.
fn set<T>(slot: &mut T, value: T) -> std::result::Result<(), String> {
    *slot = value;
    Ok(())
}

/// Every key of the metadata, in the order they are read.
pub const KEYS: &[Key] = &[
    Key {
        name: "scene",
        write: |m| Some(m.scene.clone()),
        read: |m, v| set(&mut m.scene, v.text.unwrap_or_default().to_string()),
    },
    Key {
        name: "scene_hash",
        write: |m| Some(m.scene_hash_hex()),
        read: |m, v| {
            let hash = v.required()?;
            m.scene_hash = u64::from_str_radix(hash, 16)
                .map_err(|_| format!("metadata 'scene_hash' is '{hash}', not 16 hex digits"))?;
            Ok(())
        },
    },
    Key {
        name: "width",
        write: |m| text(m.width),
        read: |m, v| set(&mut m.width, v.num()?),
    },
    Key {
        name: "height",
        write: |m| text(m.height),
        read: |m, v| set(&mut m.height, v.num()?),
    },
    Key {
        name: "spp",
        write: |m| text(m.spp),
        read: |m, v| set(&mut m.spp, v.num()?),
    },
    Key {
        name: "first_sample",
        write: |m| text(m.first_sample),
        read: |m, v| set(&mut m.first_sample, v.opt()?.unwrap_or(0)),
    },
    Key {
        name: "seed",
        write: |m| Some(m.seed.map_or_else(|| "merged".into(), |s| s.to_string())),
        read: |m, v| {
            m.seed = match v.required()? {
                "merged" => None,
                s => Some(v.number(s)?),
            };
            Ok(())
        },
    },
    Key {
        name: "merged_seeds",
        write: |m| {
            let seeds: Vec<String> = m.merged_seeds.iter().map(u64::to_string).collect();
            (!seeds.is_empty()).then(|| seeds.join(","))
        },
        read: |m, v| {
            m.merged_seeds = match v.text {
                None => Vec::new(),
                Some(t) => t
                    .split(',')
                    .map(|s| v.number(s))
                    .collect::<std::result::Result<_, _>>()?,
            };
            Ok(())
        },
    },
    Key {
        name: "sampler",
        write: |m| Some(value_name(&m.strategy.sampler)),
        read: |m, v| {
            set(
                &mut m.strategy.sampler,
                parse_value(v.required()?, "sampler")?,
            )
        },
    },
    Key {
        name: "directions",
        write: |m| Some(value_name(&m.strategy.directions)),
        read: |m, v| {
            set(
                &mut m.strategy.directions,
                parse_value(v.required()?, "directions")?,
            )
        },
    },
    Key {
        name: "lights",
        write: |m| Some(value_name(&m.strategy.lights)),
        read: |m, v| {
            v.axis("lights")?
                .map_or(Ok(()), |x| set(&mut m.strategy.lights, x))
        },
    },
    Key {
        name: "light_points",
        write: |m| Some(value_name(&m.strategy.light_points)),
        read: |m, v| {
            v.axis("light points")?
                .map_or(Ok(()), |x| set(&mut m.strategy.light_points, x))
        },
    },
    Key {
        name: "light_choice",
        write: |m| Some(value_name(&m.strategy.light_choice)),
        read: |m, v| {
            v.axis("light choice")?
                .map_or(Ok(()), |x| set(&mut m.strategy.light_choice, x))
        },
    },
    Key {
        // written for people and tools: the axes above are what is read
        name: "strategy",
        write: |m| Some(m.strategy.to_string()),
        read: |_, _| Ok(()),
    },
    Key {
        name: "max_depth",
        write: |m| text(m.max_depth),
        read: |m, v| set(&mut m.max_depth, v.num()?),
    },
    Key {
        name: "reuse",
        write: |m| m.reuse.map(|k| k.to_string()),
        read: |m, v| {
            m.reuse = v.opt()?;
            match m.reuse {
                Some(k) if !(2..=crate::render::MAX_REUSE).contains(&k) => Err(format!(
                    "metadata 'reuse' is {k}, not 2 to {}",
                    crate::render::MAX_REUSE
                )),
                _ => Ok(()),
            }
        },
    },
    Key {
        // written only where it is not the classic one
        name: "roulette",
        write: |m| (m.roulette != Roulette::Classic).then(|| m.roulette.to_string()),
        read: |m, v| {
            m.roulette = v.axis("roulette")?.unwrap_or_default();
            Ok(())
        },
    },
    Key {
        // written where a render spent them
        name: "edge_rays",
        write: |m| (m.edge_rays > 0).then(|| m.edge_rays.to_string()),
        read: |m, v| {
            m.edge_rays = v.opt()?.unwrap_or(0);
            match m.edge_rays {
                k if k > crate::render::MAX_EDGE_RAYS => Err(format!(
                    "metadata 'edge_rays' is {k}, not 0 to {}",
                    crate::render::MAX_EDGE_RAYS
                )),
                _ => Ok(()),
            }
        },
    },
    Key {
        name: "render_seconds",
        write: |m| micros(m.render_seconds),
        read: |m, v| set(&mut m.render_seconds, v.seconds()?.unwrap_or(0.0)),
    },
    Key {
        name: "nonfinite_samples",
        write: |m| text(m.nonfinite_samples),
        read: |m, v| set(&mut m.nonfinite_samples, v.opt()?.unwrap_or(0)),
    },
    Key {
        name: "pass_spp",
        write: |m| m.pass_spp.map(|p| p.to_string()),
        read: |m, v| {
            m.pass_spp = v.opt()?;
            match m.pass_spp {
                Some(0) => Err("metadata 'pass_spp' is 0".into()),
                _ => Ok(()),
            }
        },
    },
    Key {
        name: "passes",
        write: |m| {
            let sizes: Vec<String> = m.passes.iter().map(u32::to_string).collect();
            (!sizes.is_empty()).then(|| sizes.join(","))
        },
        read: |m, v| {
            m.passes = match v.text {
                None => Vec::new(),
                Some(t) => t
                    .split(',')
                    .map(|s| v.number(s))
                    .collect::<std::result::Result<_, _>>()?,
            };
            match m.passes.contains(&0) {
                true => Err("metadata 'passes' holds a pass of 0 spp".into()),
                false => Ok(()),
            }
        },
    },
    Key {
        name: "time_limit_seconds",
        write: |m| m.time_limit_seconds.map(|t| t.to_string()),
        read: |m, v| set(&mut m.time_limit_seconds, v.seconds()?),
    },
    Key {
        name: "merged_from",
        write: |m| m.merged_from.clone(),
        read: |m, v| set(&mut m.merged_from, v.text.map(String::from)),
    },
    Key {
        name: "image",
        write: |m| m.image.clone(),
        read: |m, v| set(&mut m.image, v.text.map(String::from)),
    },
    Key {
        name: "auto",
        write: |m| m.auto.clone(),
        read: |m, v| set(&mut m.auto, v.text.map(String::from)),
    },
    Key {
        name: "shard",
        write: |m| m.shard.map(|(i, n)| format!("{i}/{n}")),
        read: |m, v| {
            set(
                &mut m.shard,
                v.text.map(crate::limits::parse_shard).transpose()?,
            )
        },
    },
    Key {
        name: "requested_spp",
        write: |m| m.requested_spp.map(|r| r.to_string()),
        read: |m, v| set(&mut m.requested_spp, v.opt()?),
    },
    Key {
        name: "interrupted",
        write: |m| m.interrupted.then(|| "true".into()),
        read: |m, v| {
            m.interrupted = match v.text {
                None | Some("false") => false,
                Some("true") => true,
                Some(t) => {
                    return Err(format!(
                        "metadata 'interrupted' is '{t}', not true or false"
                    ))
                }
            };
            Ok(())
        },
    },
    Key {
        // the guide's record: this key makes it, and the guide_* keys after it must be there
        name: "guide_iterations",
        write: |m| m.guide.map(|g| g.iterations.to_string()),
        read: |m, v| {
            m.guide = v.opt::<u32>()?.map(|iterations| GuideRecord {
                iterations,
                training_spp: 0,
                training_seconds: 0.0,
                final_seconds: 0.0,
                leaves: 0,
                quad_nodes: 0,
                bytes: 0,
                combined: 0,
                final_weight: 1.0,
            });
            Ok(())
        },
    },
    Key {
        name: "guide_training_spp",
        write: |m| m.guide.map(|g| g.training_spp.to_string()),
        read: |m, v| match m.guide.as_mut() {
            Some(g) => set(&mut g.training_spp, v.num()?),
            None => Ok(()),
        },
    },
    Key {
        name: "guide_training_seconds",
        write: |m| m.guide.and_then(|g| micros(g.training_seconds)),
        read: |m, v| match m.guide.as_mut() {
            Some(g) => set(&mut g.training_seconds, v.non_negative()?),
            None => Ok(()),
        },
    },
    Key {
        name: "guide_final_seconds",
        write: |m| m.guide.and_then(|g| micros(g.final_seconds)),
        read: |m, v| match m.guide.as_mut() {
            Some(g) => set(&mut g.final_seconds, v.non_negative()?),
            None => Ok(()),
        },
    },
    Key {
        name: "guide_leaves",
        write: |m| m.guide.map(|g| g.leaves.to_string()),
        read: |m, v| match m.guide.as_mut() {
            Some(g) => set(&mut g.leaves, v.num()?),
            None => Ok(()),
        },
    },
    Key {
        name: "guide_quad_nodes",
        write: |m| m.guide.map(|g| g.quad_nodes.to_string()),
        read: |m, v| match m.guide.as_mut() {
            Some(g) => set(&mut g.quad_nodes, v.num()?),
            None => Ok(()),
        },
    },
    Key {
        name: "guide_bytes",
        write: |m| m.guide.map(|g| g.bytes.to_string()),
        read: |m, v| match m.guide.as_mut() {
            Some(g) => set(&mut g.bytes, v.num()?),
            None => Ok(()),
        },
    },
    Key {
        // absent (files before it, or an image of the final iteration alone): 0
        name: "guide_combined",
        write: |m| {
            m.guide
                .filter(|g| g.combined > 0)
                .map(|g| g.combined.to_string())
        },
        read: |m, v| match m.guide.as_mut() {
            Some(g) => set(&mut g.combined, v.opt()?.unwrap_or(0)),
            None => Ok(()),
        },
    },
    Key {
        name: "guide_final_weight",
        write: |m| {
            (m.guide)
                .filter(|g| g.combined > 0)
                .and_then(|g| micros(g.final_weight))
        },
        read: |m, v| match (m.guide.as_mut(), v.text) {
            (Some(g), Some(_)) => set(&mut g.final_weight, v.non_negative()?),
            _ => Ok(()),
        },
    },
    Key {
        name: "guide_gate",
        write: |m| m.guide_gate.clone(),
        read: |m, v| set(&mut m.guide_gate, v.text.map(String::from)),
    },
    Key {
        // the estimate's record: this key makes it, and the three after it complete it
        name: "replicates",
        write: |m| m.estimate.as_ref().map(|e| e.replicates.to_string()),
        read: |m, v| {
            m.estimate = v.opt::<u32>()?.map(|replicates| EstimateRecord {
                replicates,
                method: EstimateMethod::Undefined,
                mse: f64::NAN,
                rel_mse: f64::NAN,
            });
            Ok(())
        },
    },
    Key {
        name: "error_estimate",
        write: |m| m.estimate.as_ref().map(|e| e.method.name().to_string()),
        read: |m, v| {
            if let Some(e) = m.estimate.as_mut() {
                let name = v.required()?;
                e.method = EstimateMethod::parse(name).ok_or_else(|| {
                    format!("metadata 'error_estimate' is '{name}', not a method vrpt knows")
                })?;
            }
            Ok(())
        },
    },
    Key {
        // an undefined estimate has no numbers (NaN in memory, no key in the file)
        name: "estimated_mse",
        write: |m| {
            m.estimate
                .as_ref()
                .and_then(EstimateRecord::numbers)
                .map(|(mse, _)| format!("{mse:e}"))
        },
        read: |m, v| {
            if let Some(e) = m
                .estimate
                .as_mut()
                .filter(|e| e.method != EstimateMethod::Undefined)
            {
                e.mse = v.non_negative()?;
            }
            Ok(())
        },
    },
    Key {
        name: "estimated_rel_mse",
        write: |m| {
            m.estimate
                .as_ref()
                .and_then(EstimateRecord::numbers)
                .map(|(_, rel)| format!("{rel:e}"))
        },
        read: |m, v| {
            if let Some(e) = m
                .estimate
                .as_mut()
                .filter(|e| e.method != EstimateMethod::Undefined)
            {
                e.rel_mse = v.non_negative()?;
            }
            Ok(())
        },
    },
    Key {
        // for people and tools: `adaptive_rounds` is what is read
        name: "adaptive",
        write: |m| m.adaptive_rounds.map(|_| "true".into()),
        read: |_, _| Ok(()),
    },
    Key {
        name: "adaptive_rounds",
        write: |m| m.adaptive_rounds.map(|r| r.to_string()),
        read: |m, v| set(&mut m.adaptive_rounds, v.opt()?),
    },
    Key {
        name: "target_error",
        write: |m| m.target_error.map(|t| format!("{t:e}")),
        read: |m, v| set(&mut m.target_error, v.opt()?),
    },
];
