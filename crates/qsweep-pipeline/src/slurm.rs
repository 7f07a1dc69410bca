//! Slurm submission scripts: a job array whose task I runs `qsweep run --shard I/N`, plus a report
//! job that starts once every task has succeeded (`--dependency=afterok`). A raced pipeline gets
//! one array per possible round, each after the one before (`afterany`: a round is planned from
//! the ones before, whatever they left missing).
//!
//! The script is plain bash, run once on a login node. It holds both job scripts verbatim, as
//! quoted here-documents (nothing in them is expanded at submission), and passes every sbatch
//! option on sbatch's command line, shell-quoted, so paths with spaces survive. Paths are absolute:
//! jobs start on other nodes, and the cluster's shared filesystem is all they have in common.

use std::fmt::Write as _;
use std::path::PathBuf;

/// Everything the submission script needs, already resolved (absolute paths, validated values).
#[derive(Debug, Clone)]
pub struct Submission {
    /// The pipeline's name (job names, messages).
    pub pipeline_name: String,
    /// How the command line that generated the script read (a comment in the script).
    pub generated_by: String,
    /// The qsweep executable the jobs run.
    pub qsweep: String,
    /// Working directory of the jobs (`--chdir`).
    pub workdir: PathBuf,
    /// The pipeline file.
    pub pipeline: PathBuf,
    /// `--set` overrides, passed on to both jobs.
    pub sets: Vec<String>,
    /// `--variant` selections, passed on to both jobs.
    pub variants: Vec<String>,
    /// Pass `--yes` (accept a very large plan).
    pub yes: bool,
    /// The shared cache directory.
    pub cache: PathBuf,
    /// The report directory.
    pub report_dir: PathBuf,
    /// The report's page in it, named by the script's last line (`index.html`; a program
    /// pipeline's report: `README.md`).
    pub report_page: String,
    /// Number of array tasks, N.
    pub tasks: u32,
    /// At most this many tasks at once (`--array=1-N%M`).
    pub max_running: Option<u32>,
    /// CPUs per task, which is also each task's number of worker threads.
    pub cpus_per_task: u32,
    /// `--partition`.
    pub partition: Option<String>,
    /// `--time`.
    pub time: Option<String>,
    /// `--mem`.
    pub mem: Option<String>,
    /// `--account`.
    pub account: Option<String>,
    /// Name of the array job; the report job appends `-report`.
    pub job_name: String,
    /// Where the jobs write their logs.
    pub log_dir: PathBuf,
    /// Further sbatch options for both jobs.
    pub sbatch_args: Vec<String>,
    /// Job arrays to submit one after another: 1, or the plan's most stages (a race's rounds,
    /// then the fresh seeds: `Plan::stages_max`).
    pub rounds: u32,
}

/// The script's shell words that every job uses, resolved once.
struct Words {
    /// The qsweep executable.
    qsweep: String,
    /// The pipeline file.
    pipeline: String,
    /// The cache directory.
    cache: String,
    /// The log directory.
    logs: String,
    /// sbatch options of every job: the named ones, `--chdir`, the further ones.
    common: Vec<String>,
    /// Arguments passed on to every `qsweep` command: `--set`, `--variant`, `--yes`.
    tail: String,
}

impl Submission {
    /// The submission script.
    pub fn render(&self) -> anyhow::Result<String> {
        let w = self.words()?;
        let mut s = String::new();
        self.write_header(&mut s, &w)?;
        let (opts, body) = self.shard_job(&w)?;
        sbatch_call(&mut s, "array_job", &opts, "QSWEEP_SHARD_JOB", &body)?;
        writeln!(s)?;
        self.write_stages(&mut s, &opts, &body)?;
        let (opts, body) = self.report_job(&w)?;
        sbatch_call(&mut s, "report_job", &opts, "QSWEEP_REPORT_JOB", &body)?;
        writeln!(s)?;
        self.write_footer(&mut s, &w)?;
        Ok(s)
    }

    /// The shell words of the paths, the common sbatch options and the passed-on arguments.
    fn words(&self) -> anyhow::Result<Words> {
        let (qsweep, pipeline, cache) =
            (quote(&self.qsweep), path_word(&self.pipeline)?, path_word(&self.cache)?);
        let logs = path_word(&self.log_dir)?;
        let mut common: Vec<String> = Vec::new();
        let named = [
            ("partition", &self.partition),
            ("time", &self.time),
            ("mem", &self.mem),
            ("account", &self.account),
        ];
        for (flag, value) in named {
            if let Some(v) = value {
                common.push(format!("--{flag}={}", quote(v)));
            }
        }
        common.push(format!("--chdir={}", path_word(&self.workdir)?));
        common.extend(self.sbatch_args.iter().map(|a| quote(a)));
        let mut tail = String::new();
        for s in &self.sets {
            write!(tail, " --set {}", quote(s))?;
        }
        for v in &self.variants {
            write!(tail, " --variant {}", quote(v))?;
        }
        if self.yes {
            tail.push_str(" --yes");
        }
        Ok(Words { qsweep, pipeline, cache, logs, common, tail })
    }

    /// The script's opening comments and shell settings, and the log directory made.
    fn write_header(&self, s: &mut String, w: &Words) -> anyhow::Result<()> {
        let (n, name, logs) = (self.tasks, &self.pipeline_name, &w.logs);
        writeln!(s, "#!/usr/bin/env bash")?;
        writeln!(
            s,
            "# Submits pipeline '{name}' to Slurm: a job array of {n} tasks, task I running shard I/{n}"
        )?;
        writeln!(s, "# of the plan, and a report job that starts once every task has succeeded.")?;
        // A newline in an argument would end the comment and run the rest as a command.
        let generated_by: String =
            self.generated_by.chars().map(|c| if c.is_control() { '?' } else { c }).collect();
        writeln!(s, "# Generated by qsweep {}: {generated_by}", env!("CARGO_PKG_VERSION"))?;
        writeln!(s, "# Run it on a login node: bash THIS_FILE. Running it again is safe: each task skips")?;
        writeln!(s, "# the trials already in the cache, so only unfinished work runs.")?;
        writeln!(s, "set -euo pipefail")?;
        writeln!(s, "mkdir -p {logs}")?;
        writeln!(s)?;
        Ok(())
    }

    /// The sbatch options and script of the array job whose task I runs shard I.
    fn shard_job(&self, w: &Words) -> anyhow::Result<(Vec<String>, String)> {
        let (n, qsweep, pipeline, cache, tail) = (self.tasks, &w.qsweep, &w.pipeline, &w.cache, &w.tail);
        let array = match self.max_running {
            Some(m) => format!("1-{n}%{m}"),
            None => format!("1-{n}"),
        };
        let mut opts = vec![
            format!("--job-name={}", quote(&self.job_name)),
            format!("--array={array}"),
            format!("--cpus-per-task={}", self.cpus_per_task),
        ];
        opts.extend(w.common.iter().cloned());
        opts.push(format!("--output={}", path_word(&self.log_dir.join("%x-%A_%a.out"))?));
        let body = format!(
            "# Task I runs shard I of {n}. N is written out rather than read from $SLURM_ARRAY_TASK_COUNT\n\
             # so that resubmitting some tasks (sbatch --array=2,5 ...) keeps the same split.\n\
             exec {qsweep} run {pipeline} --cache {cache}{tail} \\\n    \
             --shard \"$SLURM_ARRAY_TASK_ID/{n}\" --jobs \"${{SLURM_CPUS_PER_TASK:-{}}}\" --no-report\n",
            self.cpus_per_task
        );
        Ok((opts, body))
    }

    /// A staged plan (a race, fresh seeds): one array per stage after the first, each starting
    /// when the one before has ended, since a stage's trials are planned from the outcomes of the
    /// stages before. Each task runs its shard of the first stage whose trials are missing.
    fn write_stages(&self, s: &mut String, opts: &[String], body: &str) -> anyhow::Result<()> {
        for round in 2..=self.rounds {
            let mut opts = opts.to_vec();
            opts[0] = format!("--job-name={}", quote(&format!("{}-round{round}", self.job_name)));
            // afterany: a failed round array (a diverged trial exits 1) must not cancel the rounds
            // after it; they plan from what is stored and run whatever is missing.
            opts.insert(1, "--dependency=afterany:\"$array_job\"".to_string());
            opts.insert(2, "--kill-on-invalid-dep=yes".to_string());
            writeln!(s, "# Stage {round} of at most {} (a race round, or the fresh seeds).", self.rounds)?;
            sbatch_call(s, "array_job", &opts, "QSWEEP_SHARD_JOB", body)?;
            writeln!(s)?;
        }
        Ok(())
    }

    /// The sbatch options and script of the report job, which starts once every task has succeeded.
    fn report_job(&self, w: &Words) -> anyhow::Result<(Vec<String>, String)> {
        let mut opts = vec![
            format!("--job-name={}", quote(&format!("{}-report", self.job_name))),
            "--dependency=afterok:\"$array_job\"".to_string(),
            // If a task fails the report can never start; cancel it rather than leave it pending.
            "--kill-on-invalid-dep=yes".to_string(),
            "--cpus-per-task=1".to_string(),
        ];
        opts.extend(w.common.iter().cloned());
        opts.push(format!("--output={}", path_word(&self.log_dir.join("%x-%j.out"))?));
        let body = format!(
            "exec {} report {} --cache {}{} --out {}\n",
            w.qsweep,
            w.pipeline,
            w.cache,
            w.tail,
            path_word(&self.report_dir)?
        );
        Ok((opts, body))
    }

    /// The lines that say what was submitted and where to watch it.
    fn write_footer(&self, s: &mut String, w: &Words) -> anyhow::Result<()> {
        let (n, logs) = (self.tasks, &w.logs);
        if self.rounds > 1 {
            writeln!(
                s,
                "echo \"submitted {} chained array jobs of {n} tasks, one per stage (race rounds, fresh seeds; the last is $array_job), and report job $report_job (starts when all succeed)\"",
                self.rounds
            )?;
        } else {
            writeln!(
                s,
                "echo \"submitted array job $array_job ({n} tasks) and report job $report_job (starts when all succeed)\""
            )?;
        }
        writeln!(s, "echo \"watch: squeue -j $array_job,$report_job   logs: \"{logs}")?;
        writeln!(s, "echo \"report: \"{}", path_word(&self.report_dir.join(&self.report_page))?)?;
        Ok(())
    }
}

/// Append `VAR=$(sbatch --parsable OPTIONS <<'DELIMITER' ... )`: the job script is a quoted
/// here-document, so sbatch receives it exactly as written.
fn sbatch_call(s: &mut String, var: &str, opts: &[String], delimiter: &str, body: &str) -> std::fmt::Result {
    writeln!(s, "{var}=$(sbatch --parsable \\")?;
    for o in opts {
        writeln!(s, "    {o} \\")?;
    }
    writeln!(s, "    <<'{delimiter}'")?;
    writeln!(s, "#!/usr/bin/env bash")?;
    s.push_str(body);
    writeln!(s, "{delimiter}")?;
    writeln!(s, ")")?;
    writeln!(s, "{var}=${{{var}%%;*}}  # --parsable prints ID or ID;CLUSTER")
}

/// `s` as one shell word: unchanged when it is plainly safe, else single-quoted.
pub fn quote(s: &str) -> String {
    let safe = |c: char| c.is_ascii_alphanumeric() || "_-+=%@:,./".contains(c);
    if !s.is_empty() && s.chars().all(safe) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// A path as one shell word; refuses what the script cannot hold (non-UTF-8, control characters).
fn path_word(p: &std::path::Path) -> anyhow::Result<String> {
    let s = p.to_str().ok_or_else(|| {
        crate::error::user_error(format!("path {} is not valid UTF-8; use a UTF-8 path", p.display()))
    })?;
    plain_text(s).map_err(|e| crate::error::user_error(format!("path {e}")))?;
    Ok(quote(s))
}

/// A value that will sit in the script: no control characters (a newline would end a line or a
/// here-document early).
pub fn plain_text(s: &str) -> Result<String, String> {
    match s.chars().find(|c| c.is_control()) {
        Some(c) => Err(format!("{s:?} contains the control character {c:?}; remove it")),
        None if s.is_empty() => Err("the value is empty".into()),
        None => Ok(s.to_string()),
    }
}

/// A Slurm time limit: minutes, MM:SS, HH:MM:SS, D-HH, D-HH:MM, D-HH:MM:SS, or `infinite`.
pub fn time_limit(s: &str) -> Result<String, String> {
    let bad = || {
        format!(
            "'{s}' is not a Slurm time limit; write minutes (90), HH:MM:SS (1:30:00) or D-HH:MM:SS (2-00:00:00)"
        )
    };
    if s.eq_ignore_ascii_case("infinite") || s.eq_ignore_ascii_case("unlimited") {
        return Ok(s.to_string());
    }
    let digits = |p: &str| !p.is_empty() && p.len() <= 9 && p.bytes().all(|b| b.is_ascii_digit());
    let (days, rest) = match s.split_once('-') {
        Some((d, r)) => (Some(d), r),
        None => (None, s),
    };
    let parts: Vec<&str> = rest.split(':').collect();
    // With or without days, the rest has one to three fields (H, H:M, H:M:S or M, M:S, H:M:S).
    if days.is_none_or(digits) && parts.len() <= 3 && parts.iter().all(|p| digits(p)) {
        Ok(s.to_string())
    } else {
        Err(bad())
    }
}

/// A Slurm memory size: a whole number with an optional K, M, G or T suffix (megabytes if none).
pub fn memory(s: &str) -> Result<String, String> {
    let digits = s.trim_end_matches(['K', 'M', 'G', 'T', 'k', 'm', 'g', 't']);
    let suffix = s.len() - digits.len();
    if !digits.is_empty() && suffix <= 1 && digits.bytes().all(|b| b.is_ascii_digit()) {
        Ok(s.to_string())
    } else {
        Err(format!("'{s}' is not a Slurm memory size; write e.g. 4G or 4000M (megabytes if no unit)"))
    }
}

/// One further sbatch option (`--qos=long`), refusing those the script sets itself.
pub fn sbatch_option(s: &str) -> Result<String, String> {
    let s = plain_text(s)?;
    if !s.starts_with('-') {
        return Err(format!("'{s}' is not an sbatch option; write it as it goes to sbatch, e.g. --qos=long"));
    }
    let name = s.split('=').next().unwrap_or_default();
    let own = ["--array", "-a", "--dependency", "-d", "--parsable", "--wrap", "--kill-on-invalid-dep"];
    if own.contains(&name) {
        return Err(format!("{name} is set by the generated script itself; leave it out"));
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn submission() -> Submission {
        Submission {
            pipeline_name: "quick".into(),
            generated_by: "qsweep slurm pipelines/quick.yaml --array 4".into(),
            qsweep: "/opt/qsweep/bin/qsweep".into(),
            workdir: "/home/ada/study".into(),
            pipeline: "/home/ada/study/pipelines/quick.yaml".into(),
            sets: vec!["seeds=3".into()],
            variants: vec![],
            yes: false,
            cache: "/home/ada/study/cache".into(),
            report_dir: "/home/ada/study/reports/quick".into(),
            report_page: "index.html".into(),
            tasks: 4,
            max_running: None,
            cpus_per_task: 8,
            partition: Some("cpu".into()),
            time: Some("1:00:00".into()),
            mem: None,
            account: None,
            job_name: "qsweep-quick".into(),
            log_dir: "/home/ada/study/slurm-logs".into(),
            sbatch_args: vec![],
            rounds: 1,
        }
    }

    #[test]
    fn a_race_chains_one_array_per_round_before_the_report() {
        let script = Submission { rounds: 3, ..submission() }.render().unwrap();
        assert_eq!(script.matches("<<'QSWEEP_SHARD_JOB'").count(), 3, "{script}");
        for round in [2, 3] {
            let at = script.find(&format!("--job-name=qsweep-quick-round{round}")).expect("named round");
            let call = &script[..at];
            let start = call.rfind("array_job=$(sbatch").unwrap();
            assert!(
                script[start..].starts_with("array_job=$(sbatch --parsable \\\n    --job-name"),
                "{script}"
            );
            assert!(script[at..].lines().nth(1).unwrap().contains("--dependency=afterany:\"$array_job\""));
        }
        // The report waits for the last round's array.
        let last = script.rfind("QSWEEP_SHARD_JOB\n)").unwrap();
        let report = script.find("--job-name=qsweep-quick-report").unwrap();
        assert!(last < report, "{script}");
        assert_eq!(
            Submission { rounds: 1, ..submission() }
                .render()
                .unwrap()
                .matches("<<'QSWEEP_SHARD_JOB'")
                .count(),
            1
        );
    }

    #[test]
    fn golden_script() {
        let got = submission().render().unwrap();
        let want = r#"#!/usr/bin/env bash
# Submits pipeline 'quick' to Slurm: a job array of 4 tasks, task I running shard I/4
# of the plan, and a report job that starts once every task has succeeded.
# Generated by qsweep 0.1.0: qsweep slurm pipelines/quick.yaml --array 4
# Run it on a login node: bash THIS_FILE. Running it again is safe: each task skips
# the trials already in the cache, so only unfinished work runs.
set -euo pipefail
mkdir -p /home/ada/study/slurm-logs

array_job=$(sbatch --parsable \
    --job-name=qsweep-quick \
    --array=1-4 \
    --cpus-per-task=8 \
    --partition=cpu \
    --time=1:00:00 \
    --chdir=/home/ada/study \
    --output=/home/ada/study/slurm-logs/%x-%A_%a.out \
    <<'QSWEEP_SHARD_JOB'
#!/usr/bin/env bash
# Task I runs shard I of 4. N is written out rather than read from $SLURM_ARRAY_TASK_COUNT
# so that resubmitting some tasks (sbatch --array=2,5 ...) keeps the same split.
exec /opt/qsweep/bin/qsweep run /home/ada/study/pipelines/quick.yaml --cache /home/ada/study/cache --set seeds=3 \
    --shard "$SLURM_ARRAY_TASK_ID/4" --jobs "${SLURM_CPUS_PER_TASK:-8}" --no-report
QSWEEP_SHARD_JOB
)
array_job=${array_job%%;*}  # --parsable prints ID or ID;CLUSTER

report_job=$(sbatch --parsable \
    --job-name=qsweep-quick-report \
    --dependency=afterok:"$array_job" \
    --kill-on-invalid-dep=yes \
    --cpus-per-task=1 \
    --partition=cpu \
    --time=1:00:00 \
    --chdir=/home/ada/study \
    --output=/home/ada/study/slurm-logs/%x-%j.out \
    <<'QSWEEP_REPORT_JOB'
#!/usr/bin/env bash
exec /opt/qsweep/bin/qsweep report /home/ada/study/pipelines/quick.yaml --cache /home/ada/study/cache --set seeds=3 --out /home/ada/study/reports/quick
QSWEEP_REPORT_JOB
)
report_job=${report_job%%;*}  # --parsable prints ID or ID;CLUSTER

echo "submitted array job $array_job (4 tasks) and report job $report_job (starts when all succeed)"
echo "watch: squeue -j $array_job,$report_job   logs: "/home/ada/study/slurm-logs
echo "report: "/home/ada/study/reports/quick/index.html
"#;
        assert_eq!(got.replace(env!("CARGO_PKG_VERSION"), "0.1.0"), want);
    }

    #[test]
    fn awkward_values_are_quoted() {
        let mut s = submission();
        s.cache = "/home/ada/my study/it's cache".into();
        s.max_running = Some(2);
        s.sbatch_args = vec!["--qos=long run".into()];
        let got = s.render().unwrap();
        assert!(got.contains(r#"--cache '/home/ada/my study/it'\''s cache'"#), "{got}");
        assert!(got.contains("--array=1-4%2 \\"), "{got}");
        assert!(got.contains("    '--qos=long run' \\"), "{got}");
        s.generated_by = "qsweep slurm 'x\nrm -rf /'".into();
        assert!(s.render().unwrap().contains(": qsweep slurm 'x?rm -rf /'\n# Run it"));
        s.log_dir = "/tmp/logs\nQSWEEP_SHARD_JOB".into();
        assert!(s.render().unwrap_err().to_string().contains("control character"));
    }

    #[test]
    fn quoting_round_trips_through_the_shell() {
        for word in ["plain", "with space", "it's", "$HOME", "a\"b", "back\\slash", "", "*"] {
            let out = std::process::Command::new("bash")
                .arg("-c")
                .arg(format!("printf %s {}", quote(word)))
                .output()
                .expect("bash runs");
            assert_eq!(String::from_utf8_lossy(&out.stdout), word, "{word:?} as {}", quote(word));
        }
    }

    #[test]
    fn value_checks() {
        for ok in ["90", "30:00", "1:30:00", "2-00", "2-12:00", "2-12:00:00", "infinite"] {
            assert_eq!(time_limit(ok).as_deref(), Ok(ok));
        }
        for bad in ["", "2h", "1:2:3:4", "-5", "1-", "1-2-3", "1 h"] {
            assert!(time_limit(bad).is_err(), "{bad:?}");
        }
        for ok in ["4000", "4G", "512m"] {
            assert_eq!(memory(ok).as_deref(), Ok(ok));
        }
        for bad in ["", "G", "4GB", "4.5G", "-1"] {
            assert!(memory(bad).is_err(), "{bad:?}");
        }
        assert!(plain_text("cpu\nrm -rf /").is_err());
        assert_eq!(sbatch_option("--qos=long").as_deref(), Ok("--qos=long"));
        assert!(sbatch_option("qos=long").is_err());
        assert!(sbatch_option("--array=1-3").is_err());
    }
}
