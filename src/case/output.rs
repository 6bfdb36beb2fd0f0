//! The case's `output` block: how often loads, body motion and probes are written, the
//! snapshots, the probes and the load filter.

use super::Point;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema, Default)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Interval between rows of loads.csv, bodies.csv and probes.csv (s); absent or
    /// "auto": a thousand rows over the run, at most 1 ms apart; null: every step.
    #[serde(default)]
    pub load_interval: LoadInterval,
    /// Interval between VTK snapshots (s); absent or "auto": ten over the run; "none" or
    /// null: none.
    #[serde(default)]
    pub snapshot_interval: SnapshotInterval,
    #[serde(default)]
    pub probes: Vec<Probe>,
    /// Width of the zero-phase moving-average filter applied to loads (s); null: automatic.
    #[serde(default)]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub filter_window: Option<f64>,
    /// Also write `energy.csv`: the fluid's kinetic and potential energy (J/m) at each
    /// load sample (the standing-wave benchmark measures its decay from it).
    #[serde(default)]
    pub energy: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Probe {
    #[schemars(extend("pattern" = r#"^[^,"\r\n]*[^\s,"][^,"\r\n]*$"#))]
    pub name: String,
    /// Where the probe reads (m): in the world, or with `body` in that body's frame (the
    /// coordinates of its polygon), on its surface.
    pub position: Point,
    /// A gauge on this body: it moves with the body and reads the pressure the fluid puts
    /// on the surface there, the pressure the load integral uses. Its position must lie
    /// within half a particle spacing of the body's surface.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body: Option<String>,
    /// Length of surface a gauge averages over (m), centred on its position and clipped
    /// to its face, as a transducer's face does; absent: a point. The reading is already
    /// the kernel average of the particles within r_e (2.5 spacings), wider than a
    /// transducer of a few millimetres at the spacings slamming is run at, so a point adds
    /// no smoothing of its own. Only with `body`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub diameter: Option<f64>,
}

/// How often the load, body and probe rows are written. Each load row is the mean over
/// its interval, stamped at the interval's end, so an interval that is long against the
/// event shifts what a reader fits (a slamming coefficient comes out high;
/// docs/validation.md). The automatic interval resolves any run with a thousand rows.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum LoadInterval {
    /// `end / AUTO_ROWS`, at most `AUTO_MAX` seconds.
    #[default]
    Auto,
    /// A row after every step (null).
    EveryStep,
    /// One row every so many seconds of simulated time.
    Every(f64),
}

impl LoadInterval {
    pub const AUTO_ROWS: f64 = 1000.0;
    pub const AUTO_MAX: f64 = 1.0e-3;

    /// Seconds between rows for a run ending at `end`, or None for a row every step.
    pub fn seconds(&self, end: f64) -> Option<f64> {
        match *self {
            Self::Auto => Some((end / Self::AUTO_ROWS).min(Self::AUTO_MAX)),
            Self::EveryStep => None,
            Self::Every(s) => Some(s),
        }
        .filter(|s| *s > 0.0 && s.is_finite())
    }
}

impl Serialize for LoadInterval {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Self::Auto => s.serialize_str("auto"),
            Self::EveryStep => s.serialize_none(),
            Self::Every(v) => s.serialize_f64(*v),
        }
    }
}

impl<'de> Deserialize<'de> for LoadInterval {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(
            match interval(d, &["auto"], "a number of seconds, \"auto\" or null")? {
                Interval::Seconds(v) => Self::Every(v),
                Interval::Word(_) => Self::Auto,
                Interval::Null => Self::EveryStep,
            },
        )
    }
}

impl JsonSchema for LoadInterval {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "LoadInterval".into()
    }
    // inline, so the field carries its bound where the contract test (and a reader of
    // the schema) looks for it
    fn inline_schema() -> bool {
        true
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "Seconds between rows, \"auto\" (a thousand rows over the run, at most 1 ms apart) or null (every step).",
            "exclusiveMinimum": 0,
            "anyOf": [
                { "type": "number", "exclusiveMinimum": 0 },
                { "type": "string", "enum": ["auto"] },
                { "type": "null" }
            ]
        })
    }
}

/// When snapshots are written: a handful by default, so that every run has something to
/// look at, at a small share of a run's time (docs/performance.md).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum SnapshotInterval {
    /// [`SnapshotInterval::AUTO_COUNT`] intervals over the run, plus t = 0.
    #[default]
    Auto,
    /// No snapshots (`"none"`, or null as in earlier cases).
    None,
    /// One every so many seconds of simulated time.
    Every(f64),
}

impl SnapshotInterval {
    pub const AUTO_COUNT: f64 = 10.0;

    /// Seconds between snapshots for a run ending at `end`, or None for no snapshots.
    pub fn seconds(&self, end: f64) -> Option<f64> {
        match *self {
            Self::Auto => Some(end / Self::AUTO_COUNT),
            Self::None => None,
            Self::Every(s) => Some(s),
        }
        .filter(|s| *s > 0.0 && s.is_finite())
    }
}

impl Serialize for SnapshotInterval {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Self::Auto => s.serialize_str("auto"),
            Self::None => s.serialize_str("none"),
            Self::Every(v) => s.serialize_f64(*v),
        }
    }
}

impl<'de> Deserialize<'de> for SnapshotInterval {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let expecting = "a number of seconds, \"auto\" or \"none\"";
        Ok(match interval(d, &["auto", "none"], expecting)? {
            Interval::Seconds(v) => Self::Every(v),
            Interval::Word("auto") => Self::Auto,
            Interval::Word(_) | Interval::Null => Self::None,
        })
    }
}

impl JsonSchema for SnapshotInterval {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "SnapshotInterval".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "Seconds between snapshots, \"auto\" (ten over the run) or \"none\" (null also means none).",
            "anyOf": [
                { "type": "number", "exclusiveMinimum": 0 },
                { "type": "string", "enum": ["auto", "none"] },
                { "type": "null" }
            ]
        })
    }
}

/// An interval field as written, before its type gives it a meaning: seconds, one of
/// its words, or null.
enum Interval {
    Seconds(f64),
    Word(&'static str),
    Null,
}

fn interval<'de, D: serde::Deserializer<'de>>(
    d: D,
    words: &'static [&'static str],
    expecting: &'static str,
) -> Result<Interval, D::Error> {
    struct Visitor {
        words: &'static [&'static str],
        expecting: &'static str,
    }
    impl serde::de::Visitor<'_> for Visitor {
        type Value = Interval;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str(self.expecting)
        }
        fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Interval, E> {
            Ok(Interval::Seconds(v))
        }
        fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Interval, E> {
            Ok(Interval::Seconds(v as f64))
        }
        fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Interval, E> {
            Ok(Interval::Seconds(v as f64))
        }
        fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Interval, E> {
            match self.words.iter().find(|w| **w == v) {
                Some(w) => Ok(Interval::Word(w)),
                None => Err(E::invalid_value(serde::de::Unexpected::Str(v), &self)),
            }
        }
        fn visit_unit<E: serde::de::Error>(self) -> Result<Interval, E> {
            Ok(Interval::Null)
        }
        fn visit_none<E: serde::de::Error>(self) -> Result<Interval, E> {
            Ok(Interval::Null)
        }
    }
    d.deserialize_any(Visitor { words, expecting })
}
