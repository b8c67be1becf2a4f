//! `--json`: the report as one JSON object on stdout, its trace streamed point by point as the
//! simulation computes it (memory stays flat however long the run), the rest of the report
//! closing the object.

use std::io::Write as _;
use std::ops::ControlFlow;

use super::{SimReport, TracePoint};
use crate::cli::{Out, Stop};

/// Writes `{"trace": [` at the first point, then each point; [`Trace::finish`] closes the
/// array and writes the rest of the report. A write that fails (the reader has gone) is kept
/// and ends the simulation through [`ControlFlow::Break`].
pub struct Trace<'a> {
    out: Option<&'a mut Out>,
    first: bool,
    failed: Option<Stop>,
}

impl<'a> Trace<'a> {
    /// A trace on `out`, or none (`None`: the text summary instead).
    #[must_use]
    pub fn new(out: Option<&'a mut Out>) -> Self {
        Self {
            out,
            first: true,
            failed: None,
        }
    }

    /// One point of the trace.
    pub fn point(&mut self, p: &TracePoint) -> ControlFlow<()> {
        if self.failed.is_some() {
            return ControlFlow::Break(());
        }
        let Some(out) = self.out.as_deref_mut() else {
            return ControlFlow::Continue(());
        };
        let sep = if self.first {
            "{\n  \"trace\": [\n    "
        } else {
            ",\n    "
        };
        self.first = false;
        let written = out
            .text(sep)
            .and_then(|()| serde_json::to_writer(out.writer(), p).map_err(Stop::from));
        match written {
            Ok(()) => ControlFlow::Continue(()),
            Err(e) => {
                self.failed = Some(e);
                ControlFlow::Break(())
            }
        }
    }

    /// Closes the trace and writes the report's other fields, ending the object.
    ///
    /// # Errors
    /// [`Stop::Closed`] when the reader has gone (also during the trace), or a write error.
    pub fn finish(mut self, report: &SimReport) -> Result<(), Stop> {
        if let Some(e) = self.failed.take() {
            return Err(e);
        }
        let Some(out) = self.out else {
            return Ok(());
        };
        if self.first {
            out.text("{\n  \"trace\": [")?;
        }
        out.text("\n  ]")?;
        let serde_json::Value::Object(fields) = serde_json::to_value(report)? else {
            return Err("the report did not serialize as an object".into());
        };
        for (key, value) in fields {
            write!(out.writer(), ",\n  \"{key}\": {value}")
                .map_err(|e| crate::cli::stop_for(&e))?;
        }
        out.line("\n}")?;
        out.flush()
    }
}
