//! What `render` says about the load (issue 50): the warnings and skipped features `info`
//! lists, each once, the list cut short when long (`info` keeps them all). `--quiet` silences
//! them.

use aperture_scene::Scene;

/// Warnings shown in full; past this, the rest are counted in one line.
const SHOWN: usize = 8;

/// The load's warnings for `render`, one line each without the `warning:` prefix: skipped
/// features, then warnings, duplicates shown once with their count, and one closing line
/// counting those left out when there are more than [`SHOWN`].
pub(crate) fn load_warnings(scene: &Scene) -> Vec<String> {
    let stats = &scene.stats;
    let mut unique: Vec<(String, usize)> = Vec::new();
    let skipped = stats
        .skipped_features
        .iter()
        .map(|f| format!("skipped: {f}"));
    for w in skipped.chain(stats.warnings.iter().cloned()) {
        match unique.iter_mut().find(|(u, _)| *u == w) {
            Some((_, n)) => *n += 1,
            None => unique.push((w, 1)),
        }
    }
    let mut out: Vec<String> = unique
        .iter()
        .take(SHOWN)
        .map(|(w, n)| match n {
            1 => w.clone(),
            n => format!("{w} ({n} times)"),
        })
        .collect();
    if unique.len() > SHOWN {
        out.push(format!(
            "… and {} more warning(s); `aperture info` lists them all",
            unique.len() - SHOWN
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(warnings: &[&str], skipped: &[&str]) -> Scene {
        let mut s = Scene::default();
        s.stats.warnings = warnings.iter().map(|w| w.to_string()).collect();
        s.stats.skipped_features = skipped.iter().map(|w| w.to_string()).collect();
        s
    }

    #[test]
    fn each_once_and_summarised_when_many() {
        let s = scene(&["a", "b", "a"], &["KHR_x"]);
        assert_eq!(load_warnings(&s), ["skipped: KHR_x", "a (2 times)", "b"]);
        let many: Vec<String> = (0..20).map(|i| format!("w{i}")).collect();
        let refs: Vec<&str> = many.iter().map(String::as_str).collect();
        let w = load_warnings(&scene(&refs, &[]));
        assert_eq!(w.len(), SHOWN + 1, "{w:?}");
        assert!(w[SHOWN].contains("12 more") && w[SHOWN].contains("aperture info"));
        assert!(load_warnings(&Scene::default()).is_empty());
    }
}
