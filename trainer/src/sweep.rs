//! Training sweeps (issue 19): a grid of network sizes × feature sets × sensor suites × seeds expanded
//! into numbered, independent jobs (`trainer sweep --job K`, one per Slurm array task), each leaving
//! `job-K.json` in a shared directory, and a merge that gathers them into one report with the seed
//! spread per configuration. A job that failed, or never left its file, is named in the report.
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::metrics::Metrics;
use crate::report::mean_spread;

/// The grid. Jobs are numbered in this order: size, then features, then suite, then seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Grid {
    pub sizes: Vec<String>,
    pub features: Vec<String>,
    pub suites: Vec<String>,
    pub seeds: Vec<u64>,
}

/// One job of the grid.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Job {
    pub index: usize,
    pub size: String,
    pub features: String,
    pub suite: String,
    pub seed: u64,
}

impl Job {
    /// The configuration a job belongs to (everything but the seed).
    pub fn config(&self) -> String {
        format!("{} / {} / {}", self.size, self.features, self.suite)
    }
}

impl Grid {
    pub fn jobs(&self) -> Vec<Job> {
        let mut v = Vec::new();
        for size in &self.sizes {
            for features in &self.features {
                for suite in &self.suites {
                    for &seed in &self.seeds {
                        v.push(Job {
                            index: v.len(),
                            size: size.clone(),
                            features: features.clone(),
                            suite: suite.clone(),
                            seed,
                        });
                    }
                }
            }
        }
        v
    }
}

/// Test-set metrics of one trained cascade pair.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Scores {
    pub alpha_float: Metrics,
    pub alpha_int8: Metrics,
    pub beta_float: Metrics,
    pub beta_int8: Metrics,
}

/// What a job leaves behind: its spec and either its scores or why it failed.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct JobResult {
    pub job: Job,
    pub scores: Option<Scores>,
    pub error: Option<String>,
    pub seconds: f64,
}

/// Where job `k` leaves its result.
pub fn result_path(dir: &Path, k: usize) -> PathBuf {
    dir.join(format!("job-{k}.json"))
}

/// Writes a job's result (under a temporary name, then renamed: never seen half written).
pub fn write_result(dir: &Path, r: &JobResult) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let path = result_path(dir, r.job.index);
    let tmp = path.with_extension("json.tmp");
    let text = serde_json::to_string_pretty(r).map_err(|e| Error::Sweep(e.to_string()))?;
    std::fs::write(&tmp, text)
        .and_then(|()| std::fs::rename(&tmp, &path))
        .map_err(|source| Error::Io {
            path: path.clone(),
            source,
        })?;
    Ok(path)
}

/// The gathered results of a grid.
pub struct Merged {
    pub grid: Grid,
    pub done: Vec<JobResult>,
    /// Jobs that wrote an error, with it.
    pub failed: Vec<(Job, String)>,
    /// Jobs with no result file (crashed, killed, or never ran).
    pub missing: Vec<Job>,
}

/// Reads every job's result from `dir`. A result whose spec is not its grid job is an error: the
/// directory holds another sweep.
pub fn merge(grid: &Grid, dir: &Path) -> Result<Merged> {
    let mut m = Merged {
        grid: grid.clone(),
        done: Vec::new(),
        failed: Vec::new(),
        missing: Vec::new(),
    };
    for job in grid.jobs() {
        let path = result_path(dir, job.index);
        let Ok(text) = std::fs::read_to_string(&path) else {
            m.missing.push(job);
            continue;
        };
        let r: JobResult = serde_json::from_str(&text)
            .map_err(|e| Error::Sweep(format!("{}: {e}", path.display())))?;
        if r.job != job {
            return Err(Error::Sweep(format!(
                "{} is job {:?}, but this grid's job {} is {:?}: another sweep's result (use another --out)",
                path.display(),
                r.job,
                job.index,
                job
            )));
        }
        match (&r.scores, &r.error) {
            (Some(_), None) => m.done.push(r),
            (_, Some(e)) => m.failed.push((job, e.clone())),
            (None, None) => m.failed.push((job, "no scores and no error".into())),
        }
    }
    Ok(m)
}

impl Merged {
    /// The sweep report: per configuration, the seeds that finished and MAE mean ± half range over
    /// them (float and deployed int8), then every failed or missing job by name.
    pub fn markdown(&self, command: &str, machine: &str) -> String {
        let mut s = String::from("# Training sweep (generated by `trainer sweep --merge`)\n\n");
        let _ = writeln!(s, "Command: `{command}`  \nMachine: {machine}\n");
        let jobs = self.grid.jobs();
        let _ = writeln!(
            s,
            "{} jobs: sizes {:?} × features {:?} × suites {:?} × seeds {:?}; {} finished, {} failed, {} missing. \
             MAE in degrees on the dataset's test flights, mean ± half the range over the finished seeds.\n",
            jobs.len(),
            self.grid.sizes,
            self.grid.features,
            self.grid.suites,
            self.grid.seeds,
            self.done.len(),
            self.failed.len(),
            self.missing.len()
        );
        s.push_str("| size / features / suite | seeds | α float | α int8 | β float | β int8 |\n|---|---|---|---|---|---|\n");
        let mut configs: Vec<String> = jobs.iter().map(Job::config).collect();
        configs.dedup();
        for c in &configs {
            let mine: Vec<&JobResult> = self.done.iter().filter(|r| r.job.config() == *c).collect();
            let rs: Vec<&Scores> = mine.iter().filter_map(|r| r.scores.as_ref()).collect();
            let seeds: Vec<String> = mine.iter().map(|r| r.job.seed.to_string()).collect();
            let cell = |f: fn(&Scores) -> f64| {
                let v: Vec<f64> = rs.iter().map(|r| f(r)).collect();
                if v.is_empty() {
                    return "–".to_string();
                }
                let (m, sp) = mean_spread(&v);
                format!("{m:.3} ± {sp:.3}")
            };
            let _ = writeln!(
                s,
                "| {c} | {} | {} | {} | {} | {} |",
                if seeds.is_empty() {
                    "none".to_string()
                } else {
                    seeds.join(", ")
                },
                cell(|r| r.alpha_float.mae),
                cell(|r| r.alpha_int8.mae),
                cell(|r| r.beta_float.mae),
                cell(|r| r.beta_int8.mae)
            );
        }
        s.push_str("\n## Failed or missing jobs\n\n");
        if self.failed.is_empty() && self.missing.is_empty() {
            s.push_str("None.\n");
        }
        for (j, e) in &self.failed {
            let _ = writeln!(
                s,
                "- **job {}** ({}, seed {}) failed: {e}",
                j.index,
                j.config(),
                j.seed
            );
        }
        for j in &self.missing {
            let _ = writeln!(
                s,
                "- **job {}** ({}, seed {}) left no result: it crashed, was killed or never ran (rerun `trainer sweep --job {}` with the same grid)",
                j.index,
                j.config(),
                j.seed,
                j.index
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Grid {
        Grid {
            sizes: vec!["small".into()],
            features: vec!["table1".into(), "dynamics".into()],
            suites: vec!["table1".into()],
            seeds: vec![1, 2],
        }
    }

    fn m(mae: f64) -> Metrics {
        Metrics {
            n: 1,
            mae,
            rmse: mae,
            p95: mae,
            max: mae,
        }
    }

    #[test]
    fn jobs_are_numbered_seed_innermost() {
        let j = grid().jobs();
        assert_eq!(j.len(), 4);
        assert_eq!((j[1].features.as_str(), j[1].seed), ("table1", 2));
        assert_eq!((j[2].features.as_str(), j[2].seed), ("dynamics", 1));
        assert!(j.iter().enumerate().all(|(i, x)| x.index == i));
    }

    #[test]
    fn merge_names_failed_and_missing_jobs_and_refuses_another_sweep() {
        let dir = std::env::temp_dir().join(format!("trainer-sweep-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let g = grid();
        let jobs = g.jobs();
        for (k, mae) in [(0, 1.0), (1, 3.0)] {
            let r = JobResult {
                job: jobs[k].clone(),
                scores: Some(Scores {
                    alpha_float: m(mae),
                    alpha_int8: m(mae),
                    beta_float: m(mae / 2.0),
                    beta_int8: m(mae / 2.0),
                }),
                error: None,
                seconds: 1.0,
            };
            write_result(&dir, &r).unwrap();
        }
        let failed = JobResult {
            job: jobs[2].clone(),
            scores: None,
            error: Some("feature needs egi".into()),
            seconds: 0.1,
        };
        write_result(&dir, &failed).unwrap();
        let merged = merge(&g, &dir).unwrap();
        assert_eq!(merged.done.len(), 2);
        assert_eq!(merged.failed.len(), 1);
        assert_eq!(merged.missing.len(), 1);
        let md = merged.markdown("cmd", "machine");
        assert!(
            md.contains("| small / table1 / table1 | 1, 2 | 2.000 ± 1.000 |"),
            "{md}"
        );
        assert!(
            md.contains("**job 2** (small / dynamics / table1, seed 1) failed: feature needs egi")
        );
        assert!(md.contains("**job 3** (small / dynamics / table1, seed 2) left no result"));
        // Another grid's results in the same directory are refused, not mixed in.
        let mut other = g.clone();
        other.seeds = vec![5, 6];
        assert!(matches!(merge(&other, &dir), Err(Error::Sweep(_))));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
