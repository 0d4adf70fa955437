//! Counts written with their noun for people to read: `1 mesh`, `2 meshes`.

/// `one` for exactly one, else `many`: `noun(1.0, "level", "levels")` is `level`, and so
/// is nothing else (`0 levels`, `0.5 levels`).
pub fn noun<'a>(n: f64, one: &'a str, many: &'a str) -> &'a str {
    if n == 1.0 {
        one
    } else {
        many
    }
}

/// `n` and its noun: `count(1, "leaf", "leaves")` is `1 leaf`.
pub fn count(n: u64, one: &str, many: &str) -> String {
    format!("{n} {}", noun(n as f64, one, many))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_is_singular_and_every_other_count_plural() {
        assert_eq!(count(1, "mesh", "meshes"), "1 mesh");
        assert_eq!(count(0, "mesh", "meshes"), "0 meshes");
        assert_eq!(count(2, "leaf", "leaves"), "2 leaves");
        assert_eq!(noun(1.0, "level", "levels"), "level");
        assert_eq!(noun(0.5, "level", "levels"), "levels");
    }
}
