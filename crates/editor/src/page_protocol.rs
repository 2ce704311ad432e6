//! What the page reads from the server instead of copying it (`GET /api/protocol`): the tile
//! frames' channels in the order of their ids ([`Channel`]), the frame's magic number and nodata
//! code, the fields of a weather period ([`WeatherPeriod`]) with their units, so that the
//! page's weather table has one column per field of the Rust type, and the colours the
//! previews use (`snowscape_render::colour`: snow, layers, the Fig. 11 stability map, viridis),
//! so that the page and the previews show a layer or a value in the same colour.

use crate::wire::{Channel, MAGIC, NODATA};
use serde::Serialize;
use snowscape_render::colour::{
    LAYER_COLOURS, Rgb, SNOW_WHITE, STABILITY_BLACK, STABILITY_BLUE, STABILITY_PURPLE, VIRIDIS,
};
use snowscape_season::scenario::WeatherPeriod;

/// One field of a weather period, as the page's weather table shows it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WeatherField {
    /// The field's name in a scenario (`[[weather]]`).
    pub name: &'static str,
    /// The column heading.
    pub label: &'static str,
    /// Its unit.
    pub unit: &'static str,
    /// Whether it may be left empty (then the scenario's default applies).
    pub optional: bool,
}

/// The fields of [`WeatherPeriod`], in its declaration order (tested against its serialised
/// keys).
pub const WEATHER_FIELDS: [WeatherField; 7] = [
    WeatherField {
        name: "from_day",
        label: "from",
        unit: "day",
        optional: false,
    },
    WeatherField {
        name: "sea_level_temperature_c",
        label: "T0",
        unit: "°C",
        optional: false,
    },
    WeatherField {
        name: "wind_from_deg",
        label: "wind from",
        unit: "°",
        optional: false,
    },
    WeatherField {
        name: "wind_speed_m_s",
        label: "wind",
        unit: "m/s",
        optional: false,
    },
    WeatherField {
        name: "rain_snow_altitude_m",
        label: "rain-snow",
        unit: "m",
        optional: false,
    },
    WeatherField {
        name: "snowfall_per_week",
        label: "snowfalls",
        unit: "/week",
        optional: false,
    },
    WeatherField {
        name: "precipitation_mm_per_day",
        label: "precip.",
        unit: "mm/day",
        optional: true,
    },
];

/// The page's protocol description.
#[derive(Debug, Clone, Serialize)]
pub struct PageProtocol {
    /// The tile frames' magic number (little-endian u32 at offset 0).
    pub frame_magic: u32,
    /// The quantised code of a nodata cell.
    pub nodata: u16,
    /// Channel names by id.
    pub channels: Vec<&'static str>,
    pub weather_fields: &'static [WeatherField],
    /// The period the page's "add period" starts from when the table is empty: a mild
    /// westerly (Cordonnier 2018 Table 2's wind direction of the examples, one snowfall a week,
    /// §5.1).
    pub weather_default: WeatherPeriod,
    pub colours: PageColours,
}

/// The previews' colours (linear RGB in [0, 1]).
#[derive(Debug, Clone, Serialize)]
pub struct PageColours {
    /// Snow.
    pub snow: Rgb,
    /// Each layer's tint.
    pub layers: LayerColours,
    /// The stability map of Cordonnier 2018 Fig. 11.
    pub stability: StabilityColours,
    /// The ramp of scalar fields, evenly spaced stops from low to high.
    pub viridis: &'static [Rgb],
}

/// Each layer's tint.
#[derive(Debug, Clone, Serialize)]
pub struct LayerColours {
    pub compacted: Rgb,
    pub stable: Rgb,
    pub unstable: Rgb,
    pub powder: Rgb,
}

/// The stability map's classes.
#[derive(Debug, Clone, Serialize)]
pub struct StabilityColours {
    pub no_snow: Rgb,
    /// Compacted or stable snow on top.
    pub stable: Rgb,
    /// Unstable snow or powder on top.
    pub unstable: Rgb,
}

impl PageProtocol {
    /// The description the server sends.
    pub fn new() -> Self {
        Self {
            frame_magic: u32::from_le_bytes(MAGIC),
            nodata: NODATA,
            channels: Channel::ALL.iter().map(|c| c.name()).collect(),
            weather_fields: &WEATHER_FIELDS,
            weather_default: WeatherPeriod {
                from_day: 0.0,
                sea_level_temperature_c: 5.0,
                wind_from_deg: 300.0,
                wind_speed_m_s: 8.0,
                rain_snow_altitude_m: 1000.0,
                snowfall_per_week: 1.0,
                precipitation_mm_per_day: None,
            },
            colours: PageColours {
                snow: SNOW_WHITE,
                layers: LayerColours {
                    compacted: LAYER_COLOURS[0],
                    stable: LAYER_COLOURS[1],
                    unstable: LAYER_COLOURS[2],
                    powder: LAYER_COLOURS[3],
                },
                stability: StabilityColours {
                    no_snow: STABILITY_BLACK,
                    stable: STABILITY_BLUE,
                    unstable: STABILITY_PURPLE,
                },
                viridis: &VIRIDIS,
            },
        }
    }
}

impl Default for PageProtocol {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weather_fields_are_the_periods_fields_in_order() {
        let p = PageProtocol::new();
        let mut full = p.weather_default.clone();
        full.precipitation_mm_per_day = Some(3.0);
        // The struct's fields in declaration order: its TOML keys (toml keeps the order).
        let text = toml::to_string(&full).unwrap();
        let keys: Vec<&str> = text
            .lines()
            .filter_map(|l| l.split_once(" = ").map(|(k, _)| k))
            .collect();
        let names: Vec<&str> = WEATHER_FIELDS.iter().map(|f| f.name).collect();
        assert_eq!(keys, names);
        for f in &WEATHER_FIELDS {
            assert_eq!(
                f.optional,
                f.name == "precipitation_mm_per_day",
                "{}",
                f.name
            );
        }
    }

    #[test]
    fn channels_are_listed_by_id() {
        let p = PageProtocol::new();
        assert_eq!(p.channels.len(), Channel::ALL.len());
        for (i, c) in Channel::ALL.iter().enumerate() {
            assert_eq!(*c as usize, i);
        }
        assert_eq!(p.channels[Channel::Powder as usize], "powder");
        assert_eq!(p.channels[Channel::SkiArea as usize], "ski_area");
    }
}
