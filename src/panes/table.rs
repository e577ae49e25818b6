//! A pane table's row as cells, written once for every way a row leaves
//! pinsight: the pane's CSV export (`render --format csv`) and the
//! clipboard copy of the selected row (`y` in the TUI). The two used to
//! spell the columns separately and had drifted (`file` against `path`,
//! `stroke_max_mm` against `stroke_max_abs_mm`); now the header and the
//! cells have one home beside the row type.

/// A row of a pane's table.
pub trait Cells {
    /// The column names, as both the CSV export and the clipboard write them.
    const HEADER: &'static [&'static str];
    /// The row's cells; `num` writes a number (the export's fixed
    /// precision, the clipboard's full precision).
    fn cells(&self, num: &dyn Fn(Option<f64>) -> String) -> Vec<String>;
}

/// The CSV document of a table's rows, numbers written by `num`.
pub(crate) fn csv_of<'a, R: Cells + 'a>(
    rows: impl IntoIterator<Item = &'a R>,
    num: &dyn Fn(Option<f64>) -> String,
) -> String {
    super::csv_table(R::HEADER, rows.into_iter().map(|r| r.cells(num)))
}
