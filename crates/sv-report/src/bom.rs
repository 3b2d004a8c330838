//! `bom.csv`: the bill of materials, one row per strip (RFC 4180: header row, CRLF line
//! ends, fields quoted when they hold a comma, a quote or a line break).

use std::fmt::Write;

use crate::summary::{strip_cut_length, strip_hub_face, strip_pierces};
use crate::{ReportError, ReportInput};

/// The columns of `bom.csv`, in order.
pub const BOM_COLUMNS: [&str; 14] = [
    "strip",
    "sheet",
    "sheet_file",
    "x_mm",
    "y_mm",
    "rotation_deg",
    "length_mm",
    "width_mm",
    "area_mm2",
    "cut_length_mm",
    "pierces",
    "units",
    "unit_labels",
    "hub_face",
];

/// The bill of materials: per strip its id, sheet number and sheet file, placement on the
/// sheet (`x_mm`, `y_mm`, `rotation_deg`: `p_sheet = R(rotation) p_strip + (x, y)`, empty
/// without nesting), bounding size, net area, cut length, pierces, number of units and the
/// unit labels (space separated, in strip order), and the face of the part its hubs come
/// out of ([`strip_hub_face`]).
pub fn bom_csv(input: &ReportInput<'_>) -> Result<String, ReportError> {
    input.validate()?;
    let placements = input.placements()?;
    let mut out = String::new();
    push_row(&mut out, BOM_COLUMNS.iter().map(|c| c.to_string()));
    for strip in &input.strips.strips {
        let labels: Vec<&str> = strip
            .units
            .iter()
            .map(|&u| input.frame.units[u].id.as_str())
            .collect();
        let (sheet, file, x, y, rotation) = match placements.get(strip.id.as_str()) {
            Some(p) => (
                p.sheet.to_string(),
                input.sheet_name(p.sheet),
                format!("{:.2}", p.translation[0]),
                format!("{:.2}", p.translation[1]),
                format!("{:.3}", p.rotation_deg),
            ),
            None => Default::default(),
        };
        push_row(
            &mut out,
            [
                strip.id.clone(),
                sheet,
                file,
                x,
                y,
                rotation,
                format!("{:.1}", strip.size_mm[0]),
                format!("{:.1}", strip.size_mm[1]),
                format!("{:.1}", strip.area_mm2),
                format!("{:.1}", strip_cut_length(strip)),
                strip_pierces(strip).to_string(),
                strip.units.len().to_string(),
                labels.join(" "),
                strip_hub_face(strip, |u| input.frame.units[u].id.clone()),
            ]
            .into_iter(),
        );
    }
    Ok(out)
}

fn push_row(out: &mut String, fields: impl Iterator<Item = String>) {
    for (i, f) in fields.enumerate() {
        if i > 0 {
            out.push(',');
        }
        let _ = write!(out, "{}", csv_field(&f));
    }
    out.push_str("\r\n");
}

/// One CSV field, quoted when it must be.
pub fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\r', '\n']) || text.starts_with(' ') || text.ends_with(' ') {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_are_quoted_only_when_needed() {
        assert_eq!(csv_field("A01"), "A01");
        assert_eq!(csv_field("A01-01 A01-02"), "A01-01 A01-02");
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
        assert_eq!(csv_field("two\nlines"), "\"two\nlines\"");
        assert_eq!(csv_field(" pad"), "\" pad\"");
        assert_eq!(csv_field(""), "");
    }
}
