//! Values of command-line flags that need more than a number: parsed here, in the library, so the
//! fuzz bench (bench/fuzz.rs) reaches the same code clap calls.

/// The default of every `--background` flag: black, as INRIA trains.
pub const DEFAULT_BACKGROUND: &str = "0,0,0";

/// `--background r,g,b`: three numbers in [0, 1].
pub fn parse_rgb(s: &str) -> Result<[f32; 3], String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected r,g,b numbers, got {s:?}"))?;
    if v.len() != 3 || v.iter().any(|c| !(0.0..=1.0).contains(c)) {
        return Err(format!("expected three values in [0, 1] as r,g,b, got {s:?}"));
    }
    Ok([v[0], v[1], v[2]])
}

/// One entry of `--labels` (clap splits the list at commas): an object label, 1..=254. 0 is the
/// background and 255 marks unsupervised pixels, so neither names an object.
pub fn parse_object_label(s: &str) -> Result<u8, String> {
    let v: u64 = s.trim().parse().map_err(|_| format!("expected an object label (a number 1..=254), got {s:?}"))?;
    match v {
        0 => Err("label 0 is the background and cannot be removed".into()),
        1..=254 => Ok(v as u8),
        _ => Err(format!("label {v} is out of range: object labels are 1..=254")),
    }
}

/// A weight: a finite number >= 0 (`--refine-hole-weight`; 0 leaves those pixels out).
pub fn parse_weight(s: &str) -> Result<f32, String> {
    let v: f32 = s.trim().parse().map_err(|_| format!("expected a number >= 0, got {s:?}"))?;
    if !v.is_finite() || v < 0.0 {
        return Err(format!("expected a finite number >= 0, got {s:?}"));
    }
    Ok(v)
}
