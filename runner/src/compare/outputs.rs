//! What CI reads from a verdict: `summary.md` (a pull-request comment or
//! `$GITHUB_STEP_SUMMARY`), `junit.xml` (one test case per scene × mode), `verdict.json`, and
//! `to-confirm.txt` (the scenes whose time regressed, to measure again).

use std::fmt::Write;
use std::path::{Path, PathBuf};

use super::verdict::{Against, Check, FailOn, Outcome, Verdict, is_time_metric};
use crate::files::markup::escape as xml;

/// Writes summary.md, junit.xml, verdict.json and, when it names scenes, to-confirm.txt into
/// `dir`, each atomically.
pub fn write_all(verdict: &Verdict, dir: &Path) -> Result<Vec<PathBuf>, String> {
    crate::files::output_folder(dir).map_err(|e| format!("--out {e}"))?;
    let write = |name: &str, text: &str| -> Result<PathBuf, String> {
        let path = dir.join(name);
        crate::files::write(&path, text.as_bytes())?;
        Ok(path)
    };
    let json = dir.join("verdict.json");
    crate::files::write_json(&json, verdict)?;
    let mut written =
        vec![write("summary.md", &summary(verdict))?, write("junit.xml", &junit(verdict))?, json];
    // The scenes to measure again, one manifest a line, for `ci/gate.sh`; none, no file (an
    // earlier compare's list must not outlive it).
    let list = dir.join(TO_CONFIRM);
    if verdict.to_confirm.is_empty() {
        match std::fs::remove_file(&list) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(format!("{}: {e}", list.display()));
            }
            _ => {}
        }
    } else {
        written.push(write(TO_CONFIRM, &(verdict.to_confirm.join("\n") + "\n"))?);
    }
    Ok(written)
}

/// The file beside verdict.json that lists its `to_confirm` manifests.
pub const TO_CONFIRM: &str = "to-confirm.txt";

/// The one-line tally: `2 regressed · 1 improved · 140 unchanged`.
pub fn tally(verdict: &Verdict) -> String {
    let parts: Vec<String> = Outcome::ALL
        .iter()
        .filter_map(|outcome| verdict.counts.get(outcome).map(|n| format!("{n} {}", outcome.name())))
        .collect();
    if parts.is_empty() { "nothing compared".into() } else { parts.join(" · ") }
}

/// Markdown: the regressions first, then improvements, then what could not be decided, then
/// one line counting what did not change.
pub fn summary(verdict: &Verdict) -> String {
    let mut out = String::new();
    let headline = if verdict.regressed { "❌ regression" } else { "✅ no regression" };
    let reported_only = verdict.checks.iter().filter(|c| c.outcome.fails() && !c.gated).count();
    let mut headline = if reported_only > 0 && !verdict.regressed {
        format!("{headline} ({reported_only} failing outcomes reported, not failed)")
    } else {
        headline.to_string()
    };
    if !time_gated(verdict) {
        headline += " — time not gated";
    }
    let _ = writeln!(out, "## aabench gate: {headline}\n");
    let _ = writeln!(out, "{}\n", tally(verdict));
    provenance(&mut out, verdict);
    let reach = super::sensitivity::lines(&verdict.checks);
    if !reach.is_empty() {
        out.push_str("The smallest slowdown each time's intervals would have called a regression:\n");
        for line in &reach {
            let _ = writeln!(out, "- {line}");
        }
        out.push('\n');
    }
    for note in &verdict.notes {
        let _ = writeln!(out, "- {note}");
    }
    if !verdict.notes.is_empty() {
        out.push('\n');
    }
    outcome_tables(&mut out, verdict);
    let unchanged = verdict.counts.get(&Outcome::Unchanged).copied().unwrap_or(0);
    let hashes = verdict
        .checks
        .iter()
        .filter(|c| c.metric == "output_hash" && c.outcome == Outcome::Unchanged)
        .count();
    let hashes = if hashes > 0 {
        format!(" ({hashes} of them an output hash that changed while every metric stayed within tolerance)")
    } else {
        String::new()
    };
    let _ = writeln!(out, "{unchanged} checks unchanged{hashes}.");
    out
}

/// Whether time was gated at all: its rule gates it (against base runs, against the baselines
/// on the machine that blessed them, or everywhere with `--fail-on all`) and a gated time check
/// had the evidence to decide.
fn time_gated(verdict: &Verdict) -> bool {
    gated_by_rule(verdict) && time_decided(verdict)
}

fn gated_by_rule(verdict: &Verdict) -> bool {
    match verdict.fail_on {
        FailOn::Quality => false,
        FailOn::All => true,
        _ => !verdict.base_run_ids.is_empty() || verdict.same_machine,
    }
}

/// Whether a gated time check reached an outcome that could have failed the gate: a gate whose
/// time checks are all `insufficient` (too few processes or frames) gated no time.
fn time_decided(verdict: &Verdict) -> bool {
    verdict.checks.iter().any(|c| c.gated && is_time_metric(&c.metric) && c.outcome != Outcome::Insufficient)
}

fn provenance(out: &mut String, verdict: &Verdict) {
    let against = match (&verdict.baseline_dir, verdict.same_platform) {
        (None, _) => "no baselines".to_string(),
        (Some(dir), true) => format!("`{}` (same platform)", dir.display()),
        (Some(dir), false) => format!("`{}` (**another platform**)", dir.display()),
    };
    let processes = match verdict.run_ids.len() {
        0 | 1 => String::new(),
        n => format!(" and {} more processes of its build", n - 1),
    };
    let _ = writeln!(out, "Run `{}`{processes}, {} tier, against {against}.", verdict.run_id, verdict.tier);
    let time = if verdict.fail_on == FailOn::Quality {
        "nothing: it is reported, not gated (`--fail-on quality`)".to_string()
    } else if verdict.fail_on == FailOn::All {
        "the baselines and any base runs, whichever machine blessed them (`--fail-on all`)".to_string()
    } else if !verdict.base_run_ids.is_empty() {
        format!(
            "the base build's {} processes on this machine (the process is the unit of evidence)",
            verdict.base_run_ids.len()
        )
    } else if verdict.same_machine {
        "the baselines (this is the machine that blessed them)".to_string()
    } else {
        "nothing: no base build was measured, and the baselines were blessed on another machine".to_string()
    };
    let time = if gated_by_rule(verdict) && !time_decided(verdict) {
        let insufficient =
            verdict.checks.iter().any(|c| is_time_metric(&c.metric) && c.outcome == Outcome::Insufficient);
        if insufficient {
            format!(
                "nothing in the end: {time}, but no time check had the evidence to decide (see Insufficient)"
            )
        } else {
            format!("nothing in the end: {time}, but no time check was made")
        }
    } else {
        time
    };
    let _ = writeln!(out, "Time is gated against {time}.\n");
    if let Some(scope) = &verdict.shard {
        let _ = writeln!(
            out,
            "Shard {}/{} of the suite: its {} scenes are compared; `aabench merge-verdicts` joins the shards' \
             verdicts and fails a baseline that none of them compared.\n",
            scope.index,
            scope.count,
            scope.scenes.len()
        );
    }
    if !verdict.confirm_run_ids.is_empty() {
        let _ = writeln!(
            out,
            "Each suspect time against the base build (regressed, or noisy with its interval above 0) was decided \
             again with {} fresh processes of the base and {} of the run: it is regressed only where all the \
             processes together put its whole interval past the tolerance and the fresh ones alone estimate it past \
             the tolerance too.\n",
            verdict.confirm_base_run_ids.len(),
            verdict.confirm_run_ids.len()
        );
    }
    if !verdict.to_confirm.is_empty() {
        let _ = writeln!(
            out,
            "Time against the base build is suspect in {}: not yet measured again in fresh processes \
             (`ci/gate.sh` does; by hand, `--confirm-runs` and `--confirm-base-runs`).\n",
            verdict.to_confirm.join(", ")
        );
    }
}

/// A table of checks per outcome that is not `unchanged`, worst first.
fn outcome_tables(out: &mut String, verdict: &Verdict) {
    for (outcome, title) in [
        (Outcome::Regressed, "Regressed"),
        (Outcome::Failed, "Failed"),
        (Outcome::Improved, "Improved"),
        (Outcome::Noisy, "Noisy (estimate past the threshold, interval not: not failed)"),
        (Outcome::Insufficient, "Insufficient (too few frames or processes to decide time: not failed)"),
        (Outcome::Missing, "Missing from the run"),
        (Outcome::New, "New (no baseline)"),
    ] {
        let rows: Vec<&Check> = verdict.checks.iter().filter(|c| c.outcome == outcome).collect();
        if rows.is_empty() {
            continue;
        }
        let _ = writeln!(out, "### {title}\n");
        let _ = writeln!(out, "| scene | mode | metric | against | detail |\n|---|---|---|---|---|");
        for check in rows {
            let against = match check.against {
                Against::Baseline => "baseline",
                Against::Base => "base build",
            };
            let gated = if check.gated || !check.outcome.fails() { "" } else { " (reported, not failed)" };
            let _ = writeln!(
                out,
                "| {} | {} | {} | {against}{gated} | {} |",
                check.scene,
                check.mode,
                check.metric,
                check.detail.replace('|', "\\|")
            );
        }
        out.push('\n');
    }
}

/// JUnit XML: a suite per scene, a test case per mode; regressed and failed checks are
/// failures carrying their numbers, new and missing modes are skipped.
pub fn junit(verdict: &Verdict) -> String {
    let mut cases: Vec<(&str, &str, Vec<&Check>)> = Vec::new();
    for check in &verdict.checks {
        match cases.iter_mut().find(|(scene, mode, _)| *scene == check.scene && *mode == check.mode) {
            Some((_, _, checks)) => checks.push(check),
            None => cases.push((&check.scene, &check.mode, vec![check])),
        }
    }
    let failing = |checks: &[&Check]| checks.iter().any(|c| c.fails());
    let mut scenes: Vec<&str> = cases.iter().map(|(scene, _, _)| *scene).collect();
    scenes.dedup();
    let total_failures = cases.iter().filter(|(_, _, checks)| failing(checks)).count();
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        out,
        "<testsuites name=\"aabench {}\" tests=\"{}\" failures=\"{total_failures}\">",
        xml(&verdict.run_id),
        cases.len()
    );
    for scene in scenes {
        let in_scene: Vec<_> = cases.iter().filter(|(s, _, _)| *s == scene).collect();
        let failures = in_scene.iter().filter(|(_, _, checks)| failing(checks)).count();
        let _ = writeln!(
            out,
            "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{failures}\">",
            xml(scene),
            in_scene.len()
        );
        for (_, mode, checks) in in_scene {
            let _ = write!(out, "    <testcase classname=\"aabench.{}\" name=\"{}\"", xml(scene), xml(mode));
            let bad: Vec<&&Check> = checks.iter().filter(|c| c.fails()).collect();
            let skipped = checks.iter().find(|c| matches!(c.outcome, Outcome::New | Outcome::Missing));
            if let Some(first) = bad.first() {
                let _ = writeln!(
                    out,
                    ">\n      <failure type=\"{}\" message=\"{}: {}\">",
                    first.outcome.name(),
                    xml(&first.metric),
                    xml(&first.detail)
                );
                for check in &bad {
                    let _ = writeln!(
                        out,
                        "{} {}: {}",
                        check.outcome.name(),
                        xml(&check.metric),
                        xml(&check.detail)
                    );
                }
                let _ = writeln!(out, "      </failure>\n    </testcase>");
            } else if let Some(check) = skipped {
                let _ = writeln!(
                    out,
                    ">\n      <skipped message=\"{}: {}\"/>\n    </testcase>",
                    check.outcome.name(),
                    xml(&check.detail)
                );
            } else {
                let noisy: Vec<String> = checks
                    .iter()
                    .filter(|c| c.outcome != Outcome::Unchanged)
                    .map(|c| format!("{} {}: {}", c.outcome.name(), c.metric, c.detail))
                    .collect();
                if noisy.is_empty() {
                    out.push_str("/>\n");
                } else {
                    let _ = writeln!(
                        out,
                        ">\n      <system-out>{}</system-out>\n    </testcase>",
                        xml(&noisy.join("\n"))
                    );
                }
            }
        }
        out.push_str("  </testsuite>\n");
    }
    out.push_str("</testsuites>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markup_is_escaped() {
        assert_eq!(xml("a<b & \"c\">'d'"), "a&lt;b &amp; &quot;c&quot;&gt;&apos;d&apos;");
    }
}
