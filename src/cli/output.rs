//! Result directories written all at once: a run writes into a temporary directory beside
//! its target (`.NAME.dpc-partial-PID`) and [`Staging::commit`] moves it into place only when
//! every file is written. A failure before that (a run that cannot start, a comparison run
//! that fails, a full disk, an interrupted process) leaves the previous results as they were,
//! and none of their files (`compare/`, `runs/`) survives into new results.
//!
//! A target that exists must be a directory of earlier results (it holds the marker file,
//! `summary.json` of a run or `summary.csv` of a sweep) or be empty: a run never replaces a
//! directory it did not write.

use std::io;
use std::path::{Path, PathBuf};

use thiserror::Error;

/// Why results could not be put in place.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum OutputError {
    /// The target exists and is not a directory.
    #[error("--out {path} exists and is not a directory")]
    NotADirectory {
        /// The target.
        path: String,
    },
    /// The target holds files that are not earlier results of this kind.
    #[error("--out {path} is not empty and holds no {marker}, so it is not a directory of earlier results that a new run may replace; choose a new or empty directory")]
    NotResults {
        /// The target.
        path: String,
        /// The file earlier results would hold.
        marker: &'static str,
    },
    /// The target is the working directory or contains it.
    #[error("--out {path} contains the working directory, which a run would replace; give a directory below it")]
    ContainsWorkingDirectory {
        /// The target.
        path: String,
    },
    /// A file system operation failed.
    #[error("cannot {action} {path}: {message}")]
    Io {
        /// What was being done (`create`, `move into place`, ...).
        action: &'static str,
        /// The path it was done to.
        path: String,
        /// The system's reason.
        message: String,
    },
}

impl OutputError {
    fn io(action: &'static str, path: &Path, e: &io::Error) -> Self {
        OutputError::Io {
            action,
            path: path.display().to_string(),
            message: e.to_string(),
        }
    }
}

/// A temporary directory that becomes `target` on [`Staging::commit`] and is removed if
/// dropped before.
#[derive(Debug)]
pub struct Staging {
    target: PathBuf,
    temp: PathBuf,
    previous: bool,
    committed: bool,
}

/// The prefix of temporary directories beside `target`.
fn sibling(target: &Path, kind: &str) -> Option<(PathBuf, String)> {
    let parent = target.parent()?;
    let name = target.file_name()?.to_string_lossy().to_string();
    Some((parent.to_path_buf(), format!(".{name}.dpc-{kind}-")))
}

impl Staging {
    /// Check that `target` may be replaced (absent, empty, or holding `marker`) and create the
    /// temporary directory beside it; temporary directories left by interrupted earlier runs
    /// into the same target are removed.
    ///
    /// # Errors
    /// [`OutputError`] when the target is not a result directory or the temporary directory
    /// cannot be created.
    pub fn new(target: &Path, marker: &'static str) -> Result<Self, OutputError> {
        let shown = target.display().to_string();
        let previous = match std::fs::metadata(target) {
            Ok(meta) if !meta.is_dir() => {
                return Err(OutputError::NotADirectory { path: shown });
            }
            Ok(_) => {
                let mut entries =
                    std::fs::read_dir(target).map_err(|e| OutputError::io("read", target, &e))?;
                let empty = entries.next().is_none();
                if !empty && !target.join(marker).is_file() {
                    return Err(OutputError::NotResults {
                        path: shown,
                        marker,
                    });
                }
                true
            }
            Err(_) => false,
        };
        // Resolved, so that `--out .` and `--out dir/` have a parent and a name.
        let target = if previous {
            std::fs::canonicalize(target).map_err(|e| OutputError::io("resolve", target, &e))?
        } else {
            let parent = target
                .parent()
                .filter(|p| !p.as_os_str().is_empty())
                .unwrap_or(Path::new("."));
            std::fs::create_dir_all(parent).map_err(|e| OutputError::io("create", parent, &e))?;
            let name = target.file_name().ok_or_else(|| OutputError::NotResults {
                path: shown.clone(),
                marker,
            })?;
            std::fs::canonicalize(parent)
                .map_err(|e| OutputError::io("resolve", parent, &e))?
                .join(name)
        };
        if std::env::current_dir()
            .and_then(std::fs::canonicalize)
            .is_ok_and(|cwd| cwd.starts_with(&target))
        {
            return Err(OutputError::ContainsWorkingDirectory { path: shown });
        }
        let (dir, prefix) = sibling(&target, "partial").ok_or(OutputError::NotResults {
            path: shown,
            marker,
        })?;
        remove_abandoned(&dir, &prefix);
        let temp = dir.join(format!("{prefix}{}", std::process::id()));
        if temp.exists() {
            std::fs::remove_dir_all(&temp).map_err(|e| OutputError::io("remove", &temp, &e))?;
        }
        std::fs::create_dir(&temp).map_err(|e| OutputError::io("create", &temp, &e))?;
        Ok(Self {
            target,
            temp,
            previous,
            committed: false,
        })
    }

    /// The directory to write the results into.
    pub fn path(&self) -> &Path {
        &self.temp
    }

    /// The target the results go to.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Whether the target held earlier results when the staging began.
    pub fn had_previous(&self) -> bool {
        self.previous
    }

    /// `cause` as the failure of a run whose results never reached the target (which keeps
    /// its earlier results, if any).
    pub fn not_written(&self, cause: crate::cli::ScenarioError) -> crate::cli::ScenarioError {
        crate::cli::ScenarioError::NotWritten {
            target: self.target().display().to_string(),
            previous: self.had_previous(),
            cause: Box::new(cause),
        }
    }

    /// The directory `name` inside the staging directory, created.
    ///
    /// # Errors
    /// [`crate::cli::ScenarioError::NotWritten`] when it cannot be created.
    pub fn subdirectory(&self, name: &str) -> Result<PathBuf, crate::cli::ScenarioError> {
        let dir = self.path().join(name);
        std::fs::create_dir_all(&dir).map_err(|e| {
            self.not_written(crate::cli::ScenarioError::Write {
                path: dir.display().to_string(),
                message: e.to_string(),
            })
        })?;
        Ok(dir)
    }

    /// Move the written results into place, replacing the earlier ones.
    ///
    /// # Errors
    /// [`OutputError::Io`] when a rename fails; the earlier results are then put back.
    pub fn commit(mut self) -> Result<(), OutputError> {
        if self.target.exists() {
            let (dir, prefix) = sibling(&self.target, "old").ok_or(OutputError::NotResults {
                path: self.target.display().to_string(),
                marker: "",
            })?;
            let old = dir.join(format!("{prefix}{}", std::process::id()));
            if old.exists() {
                std::fs::remove_dir_all(&old).map_err(|e| OutputError::io("remove", &old, &e))?;
            }
            std::fs::rename(&self.target, &old)
                .map_err(|e| OutputError::io("move aside", &self.target, &e))?;
            if let Err(e) = std::fs::rename(&self.temp, &self.target) {
                // Put the earlier results back.
                let _ = std::fs::rename(&old, &self.target);
                return Err(OutputError::io("move into place", &self.target, &e));
            }
            self.committed = true;
            // The new results are in place; a failure to delete the old ones loses nothing.
            let _ = std::fs::remove_dir_all(&old);
        } else {
            std::fs::rename(&self.temp, &self.target)
                .map_err(|e| OutputError::io("move into place", &self.target, &e))?;
            self.committed = true;
        }
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.temp);
        }
    }
}

/// The longest directory name made from a label (file systems take 255 bytes).
const NAME_CHARS: usize = 100;

/// Directory names for run labels, in order: path separators, quotes and other characters
/// that shells or file systems treat specially become `_`, long labels are cut, and a name
/// already taken (two labels that differ only in such characters, or equal labels) gets
/// `~INDEX` appended, so no two runs share a directory.
pub fn unique_names<I: IntoIterator<Item = String>>(labels: I) -> Vec<String> {
    let mut taken = std::collections::HashSet::new();
    labels
        .into_iter()
        .enumerate()
        .map(|(index, label)| {
            let mut name: String = label
                .chars()
                .take(NAME_CHARS)
                .map(|c| match c {
                    '/' | '\\' | '"' | '\'' | ' ' | ':' | '*' | '?' | '<' | '>' | '|' | '~' => '_',
                    c if c.is_control() => '_',
                    c => c,
                })
                .collect();
            if name.is_empty() || name.starts_with('.') {
                name.insert_str(0, "run");
            }
            if !taken.insert(name.clone()) {
                // `~` appears in no name made above, and the index in no other.
                name = format!("{name}~{index}");
                taken.insert(name.clone());
            }
            name
        })
        .collect()
}

/// Remove `dir/PREFIX<pid>` directories whose process no longer runs (left by a run that was
/// killed while writing). Where processes cannot be looked up (no `/proc`), nothing is removed.
fn remove_abandoned(dir: &Path, prefix: &str) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().to_string();
        let Some(pid) = name.strip_prefix(prefix) else {
            continue;
        };
        if pid.parse::<u32>().is_ok() && !Path::new("/proc").join(pid).exists() {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("dpc-output-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn results_replace_earlier_results_only_on_commit() {
        let root = scratch("commit");
        let target = root.join("out");
        std::fs::create_dir_all(target.join("compare/old")).unwrap();
        std::fs::write(target.join("summary.json"), "old").unwrap();

        // Dropped before commit: the earlier results stay, the temporary directory goes.
        let staging = Staging::new(&target, "summary.json").unwrap();
        assert!(staging.had_previous());
        std::fs::write(staging.path().join("summary.json"), "new").unwrap();
        let temp = staging.path().to_path_buf();
        drop(staging);
        assert!(!temp.exists());
        assert_eq!(
            std::fs::read_to_string(target.join("summary.json")).unwrap(),
            "old"
        );

        // Committed: the new results, and nothing of the old ones.
        let staging = Staging::new(&target, "summary.json").unwrap();
        std::fs::write(staging.path().join("summary.json"), "new").unwrap();
        staging.commit().unwrap();
        assert_eq!(
            std::fs::read_to_string(target.join("summary.json")).unwrap(),
            "new"
        );
        assert!(!target.join("compare").exists());
        let left: Vec<_> = std::fs::read_dir(&root).unwrap().collect();
        assert_eq!(left.len(), 1, "{left:?}");
        let _ = std::fs::remove_dir_all(&root);
    }

    #[test]
    fn a_directory_of_other_files_is_never_replaced() {
        let root = scratch("foreign");
        std::fs::write(root.join("notes.txt"), "mine").unwrap();
        let e = Staging::new(&root, "summary.json").unwrap_err();
        assert!(matches!(e, OutputError::NotResults { .. }), "{e}");
        assert!(e.to_string().contains("holds no summary.json"), "{e}");
        let file = root.join("notes.txt");
        let e = Staging::new(&file, "summary.json").unwrap_err();
        assert!(matches!(e, OutputError::NotADirectory { .. }), "{e}");
        // The working directory itself (empty or not) is never moved away.
        let cwd = std::env::current_dir().unwrap();
        let e = Staging::new(&cwd, "summary.json").unwrap_err();
        assert!(
            matches!(
                e,
                OutputError::ContainsWorkingDirectory { .. } | OutputError::NotResults { .. }
            ),
            "{e}"
        );
        let e = Staging::new(cwd.parent().unwrap(), "summary.json").unwrap_err();
        assert!(
            matches!(
                e,
                OutputError::ContainsWorkingDirectory { .. } | OutputError::NotResults { .. }
            ),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&root);
    }

    #[test]
    fn run_names_never_collide() {
        let names = unique_names(
            ["title=a/b", "title=a_b", "h=0.1", "h=0.1", "", "..", "x~1"].map(String::from),
        );
        assert_eq!(
            names,
            [
                "title=a_b",
                "title=a_b~1",
                "h=0.1",
                "h=0.1~3",
                "run",
                "run..",
                "x_1"
            ]
        );
        let long = unique_names(["x0=[".to_string() + &"1.0, ".repeat(100_000) + "]"]);
        assert_eq!(long[0].chars().count(), NAME_CHARS);
    }

    #[test]
    fn abandoned_temporary_directories_are_removed() {
        let root = scratch("abandoned");
        // No process has pid u32::MAX.
        let stale = root.join(format!(".out.dpc-partial-{}", u32::MAX));
        std::fs::create_dir_all(&stale).unwrap();
        let staging = Staging::new(&root.join("out"), "summary.json").unwrap();
        if Path::new("/proc/self").exists() {
            assert!(!stale.exists());
        }
        drop(staging);
        let _ = std::fs::remove_dir_all(&root);
    }
}
