//! Drawing units: `$INSUNITS` and the `--units` override, as millimetres per unit.

use std::fmt;
use std::str::FromStr;

/// A unit of length of a drawing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Units {
    /// Millimetres per drawing unit.
    pub mm: f64,
    /// The unit's name (`mm`, `in`, ...).
    pub name: &'static str,
}

/// `$INSUNITS` codes of the DXF reference with their size in millimetres.
const INSUNITS: &[(i32, &str, f64)] = &[
    (1, "in", 25.4),
    (2, "ft", 304.8),
    (3, "mi", 1_609_344.0),
    (4, "mm", 1.0),
    (5, "cm", 10.0),
    (6, "m", 1000.0),
    (7, "km", 1_000_000.0),
    (8, "microinch", 25.4e-6),
    (9, "mil", 0.0254),
    (10, "yd", 914.4),
    (11, "angstrom", 1e-7),
    (12, "nm", 1e-6),
    (13, "um", 1e-3),
    (14, "dm", 100.0),
    (15, "dam", 10_000.0),
    (16, "hm", 100_000.0),
    (17, "Gm", 1e12),
    (18, "au", 1.495_978_707e14),
    (19, "ly", 9.460_730_472_580_8e18),
    (20, "pc", 3.085_677_581_49e19),
    (21, "us-ft", 1200.0 / 3937.0 * 1000.0),
];

impl Units {
    /// Millimetres.
    pub const MM: Units = Units {
        mm: 1.0,
        name: "mm",
    };

    /// The unit of a `$INSUNITS` code: `Ok(None)` for 0 (unitless), `Err` for a code the
    /// DXF reference does not define.
    pub fn from_insunits(code: i32) -> Result<Option<Units>, String> {
        if code == 0 {
            return Ok(None);
        }
        INSUNITS
            .iter()
            .find(|u| u.0 == code)
            .map(|&(_, name, mm)| Some(Units { mm, name }))
            .ok_or_else(|| {
                format!("$INSUNITS {code} is not a unit of length of the DXF reference (1-21)")
            })
    }
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name)
    }
}

impl FromStr for Units {
    type Err = String;

    /// `mm`, `cm`, `m`, `in` (or `inch`), `ft`, ... (the names of the table above).
    fn from_str(s: &str) -> Result<Self, String> {
        let k = match s.trim().to_ascii_lowercase().as_str() {
            "inch" | "inches" => "in",
            "millimetre" | "millimeter" => "mm",
            "metre" | "meter" => "m",
            other => return find(other).ok_or_else(|| unknown(s)),
        };
        find(k).ok_or_else(|| unknown(s))
    }
}

fn find(name: &str) -> Option<Units> {
    INSUNITS
        .iter()
        .find(|u| u.1.eq_ignore_ascii_case(name))
        .map(|&(_, name, mm)| Units { mm, name })
}

fn unknown(s: &str) -> String {
    format!("unknown unit {s:?}: use mm, cm, m, in, ft (or another $INSUNITS name)")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_and_names() {
        assert_eq!(Units::from_insunits(1).unwrap().unwrap().mm, 25.4);
        assert_eq!(Units::from_insunits(6).unwrap().unwrap().name, "m");
        assert_eq!(Units::from_insunits(0).unwrap(), None);
        assert!(Units::from_insunits(99).unwrap_err().contains("99"));
        assert_eq!("inch".parse::<Units>().unwrap().mm, 25.4);
        assert_eq!("M".parse::<Units>().unwrap().mm, 1000.0);
        assert!("furlong".parse::<Units>().is_err());
    }
}
