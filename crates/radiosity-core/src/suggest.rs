//! The nearest known name to a typo, for every "did you mean" the workspace gives: solver
//! names, backend names and parameters, scene names, parameters and files, stop rules.
//!
//! A candidate is suggested when it is at most [`suggestion_distance`] edits from the word
//! (Damerau–Levenshtein: insertions, deletions, substitutions and transpositions of adjacent
//! characters, from `strsim`), the nearest one, the first on a tie; the word itself is never
//! suggested. Failing that, a candidate of at least three characters that begins the word, or
//! that the word begins, is suggested (`eps` for `epsilon`, `columns` for `col`).
//!
//! Reference: Damerau 1964, "A technique for computer detection and correction of spelling
//! errors", Communications of the ACM 7(3).

/// The most edits at which a name of `length` characters (the longer of the two compared) is
/// suggested: a quarter of it, at least 1.
pub fn suggestion_distance(length: usize) -> usize {
    (length / 4).max(1)
}

/// The candidate nearest to `word`, if one is near enough to be a typo of it (module doc).
pub fn nearest<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let mut best: Option<(usize, &str)> = None;
    let mut prefix = None;
    for candidate in candidates {
        let (short, long) = if candidate.len() < word.len() { (candidate, word) } else { (word, candidate) };
        if prefix.is_none() && short != long && short.chars().count() >= 3 && long.starts_with(short) {
            prefix = Some(candidate);
        }
        let distance = strsim::damerau_levenshtein(word, candidate);
        if distance > 0 && best.is_none_or(|(d, _)| distance < d) {
            best = Some((distance, candidate));
        }
    }
    let near = best.filter(|&(d, c)| d <= suggestion_distance(word.chars().count().max(c.chars().count())));
    near.map(|(_, c)| c).or(prefix)
}

/// ` (did you mean 'NAME'?)` for the nearest candidate, or nothing: the clause every
/// "unknown …" error places after the word it refuses.
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    nearest(word, candidates).map(|s| format!(" (did you mean '{s}'?)")).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typos_get_the_nearest_name_and_strangers_none() {
        let names = ["columns", "steps", "rays", "links", "rms", "residual", "time"];
        assert_eq!(nearest("colums", names), Some("columns"));
        assert_eq!(nearest("setps", names), Some("steps"));
        assert_eq!(nearest("frobnicate", names), None);
        // The word itself is not a suggestion.
        assert_eq!(nearest("rays", names), None);
        assert_eq!(did_you_mean("epsilon", ["eps", "epsilons"]), " (did you mean 'epsilons'?)");
        assert_eq!(did_you_mean("xyz", ["eps"]), "");
        // A name the word begins with, or that begins with the word, when none is near.
        assert_eq!(nearest("epsilon", ["eps", "shadows"]), Some("eps"));
        assert_eq!(nearest("resid", ["rms", "residual"]), Some("residual"));
        assert_eq!(nearest("ep", ["eps"]), Some("eps"));
    }
}
