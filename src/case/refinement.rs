//! The case's `refinement`: where particles may be coarser than `particle_spacing`.
//!
//! `"auto"` (the default) keeps `particle_spacing` around each moving body's path and
//! doubles it elsewhere, and is uniform in a scene without a moving body; `"none"` keeps
//! one spacing everywhere; `{"fine": [{"min": …, "max": …}, …]}` names the fine boxes
//! itself.

use super::Domain;
use schemars::JsonSchema;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Particle spacing that varies in space (`engine::refinement` builds the layout).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Refinement {
    /// One spacing everywhere.
    None,
    /// Fine around each moving body's swept path, twice as coarse beyond and four times
    /// as coarse far from it; one spacing everywhere without a moving body.
    #[default]
    Auto,
    /// Fine inside the given boxes, twice as coarse elsewhere.
    Regions(RefinementRegions),
}

/// Explicit fine regions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RefinementRegions {
    /// Boxes kept at `particle_spacing`; the fluid outside all of them is laid out at
    /// twice that spacing.
    #[schemars(extend("minItems" = 1))]
    pub fine: Vec<Domain>,
}

/// Where particles may be coarser than `particle_spacing`: "auto", "none" or fine boxes.
#[derive(Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
enum Form {
    Mode(RefinementMode),
    Regions(RefinementRegions),
}

#[derive(Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
enum RefinementMode {
    /// One spacing everywhere.
    None,
    /// Fine around each moving body's swept path, twice as coarse beyond and four times
    /// as coarse far from it; one spacing everywhere without a moving body.
    Auto,
}

impl Serialize for Refinement {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Refinement::None => Form::Mode(RefinementMode::None),
            Refinement::Auto => Form::Mode(RefinementMode::Auto),
            Refinement::Regions(r) => Form::Regions(r.clone()),
        }
        .serialize(s)
    }
}

impl<'de> Deserialize<'de> for Refinement {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let value = serde_json::Value::deserialize(d)?;
        match value {
            serde_json::Value::String(s) => match s.as_str() {
                "none" => Ok(Refinement::None),
                "auto" => Ok(Refinement::Auto),
                other => Err(serde::de::Error::custom(format!(
                    "unknown refinement `{other}`: expected \"none\", \"auto\" or an object \
                     with `fine` boxes"
                ))),
            },
            serde_json::Value::Object(_) => RefinementRegions::deserialize(value)
                .map(Refinement::Regions)
                .map_err(serde::de::Error::custom),
            _ => Err(serde::de::Error::custom(
                "expected \"none\", \"auto\" or an object with `fine` boxes",
            )),
        }
    }
}

impl JsonSchema for Refinement {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Refinement".into()
    }
    fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
        Form::json_schema(generator)
    }
}

impl Refinement {
    pub fn is_auto(&self) -> bool {
        *self == Refinement::Auto
    }
}
