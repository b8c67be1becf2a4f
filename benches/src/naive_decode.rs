//! The obvious decoder: test the cams one by one, as a first implementation would.

/// Decodes a 13-cam word bit by bit; `None` for no cams, a parity error or bits above bit 12.
#[must_use]
pub fn decode(raw: u16) -> Option<u16> {
    if raw == 0 || raw >= 1 << 13 {
        return None;
    }
    let mut ones = 0;
    for bit in 0..13 {
        if raw & (1 << bit) != 0 {
            ones += 1;
        }
    }
    if ones % 2 != 0 {
        return None;
    }
    let number = raw & 0x0FFF;
    (number != 0).then_some(number)
}
