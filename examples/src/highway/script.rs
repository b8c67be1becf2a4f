//! The scripted workload: one command per line instead of the random mix.

use regler_panel_link::highway::Message;

/// Parses a workload script: one command per line, `CRATE STATION SUBADDRESS FUNCTION [DATA]`
/// (data for F16–F23, decimal or 0x-hex); `#` starts a comment.
///
/// # Errors
/// The line and what is wrong with it.
pub fn parse_script(text: &str, crates: u8) -> Result<Vec<Message>, String> {
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let at = |e: String| format!("script line {}: {e}", k + 1);
        let number = |t: &str| -> Result<u32, String> {
            match t.strip_prefix("0x") {
                Some(hex) => u32::from_str_radix(hex, 16),
                None => t.parse(),
            }
            .map_err(|_| format!("'{t}' is not a number"))
        };
        let fields: Vec<&str> = line.split_whitespace().collect();
        if !(4..=5).contains(&fields.len()) {
            return Err(at(format!(
                "expected CRATE STATION SUBADDRESS FUNCTION [DATA], got '{line}'"
            )));
        }
        let small = |t: &str| -> Result<u8, String> {
            u8::try_from(number(t)?).map_err(|_| format!("'{t}' is too large"))
        };
        let command = Message::Command {
            crate_address: small(fields[0]).map_err(at)?,
            station: small(fields[1]).map_err(at)?,
            subaddress: small(fields[2]).map_err(at)?,
            function: small(fields[3]).map_err(at)?,
            data: fields.get(4).map(|t| number(t)).transpose().map_err(at)?,
        };
        command.validate().map_err(|e| at(e.to_string()))?;
        if !(1..=crates).contains(&command.crate_address()) {
            return Err(at(format!(
                "crate {} is not on the loop (1..={crates})",
                command.crate_address()
            )));
        }
        out.push(command);
    }
    if out.is_empty() {
        return Err("the script has no commands".into());
    }
    Ok(out)
}
