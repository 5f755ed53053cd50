//! Names from a case file (and from the mesh's physical groups it refers to) end up in file
//! names (`contact_<pair>_0001.csv`, per-level folders of a study) and in CSV column headers
//! (`<pair>_normal_force`). A name like `x/../../ESCAPED` would then write outside the
//! output folder, and a comma or a line break would break the CSV tables, so every such name
//! is checked here, once, when the case is read.

/// Longest name accepted: file names are limited to 255 bytes on common file systems, and a
/// name is one part of a file name.
pub const MAX_NAME_LEN: usize = 64;

/// Device names that Windows reserves in every folder, with or without an extension.
const RESERVED: [&str; 22] = [
    "CON", "PRN", "AUX", "NUL", "COM1", "COM2", "COM3", "COM4", "COM5", "COM6", "COM7", "COM8",
    "COM9", "LPT1", "LPT2", "LPT3", "LPT4", "LPT5", "LPT6", "LPT7", "LPT8", "LPT9",
];

/// Whether `c` may appear in a name: ASCII letters and digits, `_`, `-`, `.`, `+`, and
/// blanks between words (gmsh physical names often contain them).
fn allowed(c: char) -> bool {
    c.is_ascii_alphanumeric() || "_-.+ ".contains(c)
}

/// Checks that `name` is safe as part of a file name and of a CSV header; the error says
/// what is wrong (the caller adds the case-file key).
pub fn check_name(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("a name must not be empty".into());
    }
    if name.len() > MAX_NAME_LEN {
        return Err(format!(
            "a name may have at most {MAX_NAME_LEN} characters (this one has {})",
            name.chars().count()
        ));
    }
    if let Some(c) = name.chars().find(|&c| !allowed(c)) {
        return Err(format!(
            "the character {c:?} is not allowed in a name (it becomes part of file names): \
             use letters, digits, '_', '-', '.', '+' and blanks"
        ));
    }
    if name.starts_with(' ') || name.ends_with(' ') {
        return Err("a name must not start or end with a blank".into());
    }
    if name.chars().all(|c| c == '.') {
        return Err("a name must not consist of dots only".into());
    }
    let stem = name.split('.').next().unwrap_or(name).trim_end();
    if RESERVED.iter().any(|r| r.eq_ignore_ascii_case(stem)) {
        return Err(format!(
            "`{stem}` is a reserved device name on Windows and cannot be part of a file name"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ordinary_names_pass() {
        for name in [
            "fit",
            "lower_top-upper.bottom",
            "my body",
            "pair+1",
            "CONTACT",
            "con1",
        ] {
            assert_eq!(check_name(name), Ok(()), "{name}");
        }
    }

    #[test]
    fn unsafe_names_are_rejected() {
        let long = "a".repeat(MAX_NAME_LEN + 1);
        for name in [
            "",
            "x/../../ESCAPED",
            "/etc/passwd",
            "..",
            ".",
            "a\\b",
            "nul\0byte",
            "line\nbreak",
            "tab\there",
            "comma,name",
            "quote\"",
            "CON",
            "lpt1.csv",
            "Aux ",
            " lead",
            "é",
            long.as_str(),
        ] {
            assert!(check_name(name).is_err(), "{name:?} accepted");
        }
        assert_eq!(check_name(&long[1..]), Ok(()));
    }
}
