//! Reports as data, and the one renderer per format.
//!
//! A [`Report`] is a title, a list of [`Section`]s made of [`Block`]s (check tables, quantity
//! tables, other tables, figures, notes, text) and a machine-readable payload. The renderers in
//! [`render`] write it as terminal text, `report.md`, `report.html` and `report.json`; no
//! report writes a table by hand, so the four stay the same table.
//!
//! Conventions, in one place:
//! - numbers in [`Cell::Num`], checks and quantities are printed with significant digits
//!   ([`fmt_sig`]: four unless a row says otherwise); percentages with a fixed count of decimals;
//! - a check's margin is how far inside its limit the value is, as a fraction of the limit
//!   (negative: violated); where value and limit are themselves percentages the margin is the
//!   difference in percentage points ([`CheckRow::in_points`]);
//! - `report.json` is [`Report::data`]: the run's own serialised data under its stable ids, the
//!   schema the `--json` of each command documents.
//!
//! The FE command reports (mode table, mesh summary, static summary) are in [`fe`], re-exported
//! here.

pub mod fe;
pub mod render;

pub use fe::*;

use serde::Serialize;

/// A whole report: what one run of a command or machine produced.
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// Heading (`design: built-in paper design`).
    pub title: String,
    /// The sections, in reading order (checks first where there are checks).
    pub sections: Vec<Section>,
    /// The machine-readable payload (`--json`, `report.json`): the run's serialised data.
    pub data: serde_json::Value,
}

/// One titled part of a report.
#[derive(Clone, Debug, Default)]
pub struct Section {
    /// Stable id (anchor in HTML).
    pub id: String,
    /// Heading; an empty title prints no heading.
    pub title: String,
    /// Contents, in order.
    pub blocks: Vec<Block>,
}

/// A piece of a section.
#[derive(Clone, Debug)]
pub enum Block {
    /// Pass/fail checks: value, limit, margin, verdict.
    Checks(Vec<CheckRow>),
    /// Computed quantities, each with its unit and, where there is one, the published value.
    Quantities(Vec<QuantityRow>),
    /// Any other table.
    Table(Table),
    /// A picture written beside the report.
    Figure(Figure),
    /// Notes (`note: …` in text, a list elsewhere).
    Notes(Vec<String>),
    /// A paragraph (kept as written: line breaks are kept in text and markdown).
    Text(String),
}

/// One check: the value a run gives against its limit.
#[derive(Clone, Debug, Serialize)]
pub struct CheckRow {
    /// Stable id.
    #[serde(skip)]
    pub id: String,
    /// What is checked.
    pub name: String,
    /// Unit of value and limit (empty: dimensionless).
    #[serde(skip_serializing_if = "String::is_empty")]
    pub unit: String,
    /// The value.
    pub value: f64,
    /// The limit.
    pub limit: f64,
    /// How far inside the limit (negative: violated): a fraction of the limit, or percentage
    /// points when value and limit are percentages.
    pub margin: f64,
    /// Passed.
    pub ok: bool,
    /// The value must stay at or below the limit (else at or above).
    #[serde(skip)]
    pub upper: bool,
    /// The margin is in percentage points, not a fraction of the limit.
    #[serde(skip)]
    pub points: bool,
}

impl CheckRow {
    /// A check whose value must stay at or below `limit`.
    pub fn upper(id: &str, name: &str, unit: &str, value: f64, limit: f64) -> Self {
        Self::new(id, name, unit, value, limit, true)
    }

    /// A check whose value must stay at or above `limit`.
    pub fn lower(id: &str, name: &str, unit: &str, value: f64, limit: f64) -> Self {
        Self::new(id, name, unit, value, limit, false)
    }

    fn new(id: &str, name: &str, unit: &str, value: f64, limit: f64, upper: bool) -> Self {
        let margin = if upper {
            (limit - value) / limit.abs()
        } else {
            (value - limit) / limit.abs()
        };
        // A NaN value or limit fails (a comparison with NaN is false either way).
        let ok = if upper { value <= limit } else { value >= limit };
        CheckRow {
            id: id.into(),
            name: name.into(),
            unit: unit.into(),
            value,
            limit,
            margin,
            ok,
            upper,
            points: false,
        }
    }

    /// Value and limit are percentages (or fractions shown as such): the margin becomes the
    /// difference between them, not a percentage of a percentage.
    pub fn in_points(mut self) -> Self {
        self.margin = if self.upper {
            self.limit - self.value
        } else {
            self.value - self.limit
        };
        self.points = true;
        self
    }
}

/// One computed quantity.
#[derive(Clone, Debug, Serialize)]
pub struct QuantityRow {
    /// Stable id.
    #[serde(skip)]
    pub id: String,
    /// What.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// The value.
    pub value: f64,
    /// Significant digits to print.
    #[serde(skip)]
    pub digits: usize,
    /// The published value, where there is one.
    pub published: Option<f64>,
    /// Source of the published value, or why the two differ.
    pub note: String,
}

impl QuantityRow {
    /// A quantity printed with four significant digits, with no published value.
    pub fn new(id: &str, name: &str, unit: &str, value: f64) -> Self {
        QuantityRow {
            id: id.into(),
            name: name.into(),
            unit: unit.into(),
            value,
            digits: 4,
            published: None,
            note: String::new(),
        }
    }

    /// With a published value to compare against.
    pub fn published(mut self, p: Option<f64>) -> Self {
        self.published = p;
        self
    }

    /// With a note.
    pub fn note(mut self, n: &str) -> Self {
        self.note = n.into();
        self
    }

    /// Relative difference to the published value (`value / published − 1`), where there is one.
    pub fn difference(&self) -> Option<f64> {
        self.published.map(|p| self.value / p - 1.0)
    }
}

/// A table of rows of cells under headed columns.
#[derive(Clone, Debug, Default)]
pub struct Table {
    /// Stable id.
    pub id: String,
    /// Caption printed above the table, if any.
    pub caption: Option<String>,
    /// Columns.
    pub columns: Vec<Column>,
    /// Rows, each as long as `columns`.
    pub rows: Vec<Vec<Cell>>,
}

/// A table column: header and unit.
#[derive(Clone, Debug)]
pub struct Column {
    /// Header.
    pub header: String,
    /// Unit, shown after the header (`f (Hz)`).
    pub unit: Option<String>,
}

impl Column {
    /// A column headed `header`, in `unit` if given.
    pub fn new(header: &str, unit: Option<&str>) -> Self {
        Column {
            header: header.into(),
            unit: unit.map(Into::into),
        }
    }

    /// The header as printed: `header (unit)`.
    pub fn heading(&self) -> String {
        match &self.unit {
            Some(u) if !u.is_empty() => format!("{} ({u})", self.header),
            _ => self.header.clone(),
        }
    }
}

/// One table cell.
#[derive(Clone, Debug)]
pub enum Cell {
    /// A number with `digits` significant digits.
    Num {
        /// The number.
        value: f64,
        /// Significant digits.
        digits: usize,
    },
    /// A number with a fixed count of decimals.
    Fixed {
        /// The number.
        value: f64,
        /// Decimals.
        decimals: usize,
    },
    /// A fraction shown as a percentage with `decimals` decimals (`0.123` → `12.3 %`).
    Pct {
        /// The fraction.
        value: f64,
        /// Decimals.
        decimals: usize,
    },
    /// Text.
    Text(String),
    /// Nothing (printed as a dash in text tables).
    Empty,
}

impl Cell {
    /// A number with four significant digits.
    pub fn num(value: f64) -> Self {
        Cell::Num { value, digits: 4 }
    }

    /// Text.
    pub fn text(t: impl Into<String>) -> Self {
        Cell::Text(t.into())
    }

    /// The cell as printed.
    pub fn show(&self) -> String {
        match self {
            Cell::Num { value, digits } => fmt_sig(*value, *digits),
            Cell::Fixed { value, decimals } => format!("{value:.decimals$}"),
            Cell::Pct { value, decimals } => format!("{:.decimals$} %", 100.0 * value),
            Cell::Text(t) => t.clone(),
            Cell::Empty => "–".into(),
        }
    }

    /// Numbers are right-aligned.
    pub fn numeric(&self) -> bool {
        matches!(self, Cell::Num { .. } | Cell::Fixed { .. } | Cell::Pct { .. })
    }
}

/// A figure: an SVG file written into the report's folder.
#[derive(Clone, Debug)]
pub struct Figure {
    /// Stable id.
    pub id: String,
    /// File name relative to the report's folder.
    pub file: String,
    /// Caption.
    pub caption: String,
}

/// A number with `digits` significant digits, plain or with an exponent (`184.2`, `4.990e6`):
/// the one formatter every report uses.
pub fn fmt_sig(x: f64, digits: usize) -> String {
    crate::io::fmt_sig(x, digits)
}

impl Report {
    /// An empty report titled `title` carrying `data` as its JSON payload.
    pub fn new(title: impl Into<String>, data: serde_json::Value) -> Self {
        Report {
            title: title.into(),
            sections: Vec::new(),
            data,
        }
    }

    /// Adds a section and returns it for filling.
    pub fn section(&mut self, id: &str, title: &str) -> &mut Section {
        self.sections.push(Section {
            id: id.into(),
            title: title.into(),
            blocks: Vec::new(),
        });
        self.sections.last_mut().expect("just pushed")
    }

    /// Every check of the report, in order.
    pub fn checks(&self) -> impl Iterator<Item = &CheckRow> {
        self.sections.iter().flat_map(|s| &s.blocks).flat_map(|b| match b {
            Block::Checks(c) => c.as_slice(),
            _ => &[],
        })
    }

    /// "all passed" or "2 of 6 failed" (with `failed` spelt as given); `None` without checks.
    pub fn checks_summary(&self, failed_word: &str) -> Option<String> {
        let all: Vec<_> = self.checks().collect();
        if all.is_empty() {
            return None;
        }
        let failed = all.iter().filter(|c| !c.ok).count();
        Some(if failed == 0 {
            "all passed".to_string()
        } else {
            format!("{failed} of {} {failed_word}", all.len())
        })
    }
}

impl Section {
    /// Appends a block.
    pub fn push(&mut self, b: Block) -> &mut Self {
        self.blocks.push(b);
        self
    }
}

/// Serialises items as a JSON object keyed by each item's id (`{"c12": {...}, ...}`): the
/// stable-id form of check and quantity lists in `report.json`.
pub fn by_id<T: Serialize, S: serde::Serializer>(
    items: &[T],
    id: impl Fn(&T) -> &str,
    ser: S,
) -> std::result::Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut m = ser.serialize_map(Some(items.len()))?;
    for x in items {
        m.serialize_entry(id(x), x)?;
    }
    m.end()
}
