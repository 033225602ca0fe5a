//! The file store, the default: one JSON file per registered scenario in a
//! directory of this replica's own.
//!
//! A write is atomic and durable before it is acknowledged: the file is
//! written under a temporary name, fsynced, renamed over its final name, and
//! the directory is fsynced. A crash (even `kill -9`) at any moment leaves
//! either the old state or the new one. On load, a file that is corrupt,
//! truncated or foreign is reported and skipped, never fatal; it is never
//! overwritten silently either: a save that would replace it first moves it
//! aside under a `.corrupt-…` name and says so in the log. Statistics are
//! not stored; they are rebuilt on load.

use std::fs::{self, File};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::scenario::{Scenario, ScenarioSpec};

/// Version of the file format.
pub const FORMAT: u32 = 1;

/// What a file holds.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Stored {
    format: u32,
    id: String,
    spec: ScenarioSpec,
}

/// The store's directory.
#[derive(Debug, Clone)]
pub struct Store {
    dir: PathBuf,
}

/// True for ids that are safe as file names (derived ids are `s-` and hex).
fn safe_id(id: &str) -> bool {
    !id.is_empty()
        && id.len() <= 64
        && id
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-')
}

impl Store {
    /// Opens (creating if needed) the store at `dir` and loads every valid
    /// scenario in it. Invalid files are logged and skipped.
    pub fn open(dir: &Path) -> io::Result<(Store, Vec<Scenario>)> {
        fs::create_dir_all(dir)?;
        let store = Store {
            dir: dir.to_path_buf(),
        };
        let mut loaded = Vec::new();
        let mut entries: Vec<PathBuf> = fs::read_dir(dir)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "json"))
            .collect();
        entries.sort();
        for path in entries {
            match Self::load(&path) {
                Ok(s) => loaded.push(s),
                Err(reason) => tracing::warn!(
                    file = %path.display(),
                    %reason,
                    "skipping a scenario file that cannot be loaded"
                ),
            }
        }
        Ok((store, loaded))
    }

    fn load(path: &Path) -> Result<Scenario, String> {
        let bytes = fs::read(path).map_err(|e| e.to_string())?;
        let stored: Stored =
            serde_json::from_slice(&bytes).map_err(|e| format!("not a scenario file: {e}"))?;
        if stored.format != FORMAT {
            return Err(format!(
                "format {} (this server reads {FORMAT})",
                stored.format
            ));
        }
        let scenario = Scenario::new(stored.spec).map_err(|e| format!("invalid spec: {e}"))?;
        if scenario.id != stored.id {
            return Err(format!(
                "id {} does not match its spec ({})",
                stored.id, scenario.id
            ));
        }
        let expected = format!("{}.json", scenario.id);
        if path
            .file_name()
            .is_none_or(|n| n.to_string_lossy() != expected)
        {
            return Err(format!("file name should be {expected}"));
        }
        Ok(scenario)
    }

    fn path(&self, id: &str) -> io::Result<PathBuf> {
        if !safe_id(id) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("unsafe id {id:?}"),
            ));
        }
        Ok(self.dir.join(format!("{id}.json")))
    }

    /// Writes a scenario durably (see the module docs). Blocking I/O.
    pub fn save(&self, scenario: &Scenario) -> io::Result<()> {
        let path = self.path(&scenario.id)?;
        if path.exists() && Self::load(&path).is_err() {
            let aside = path.with_extension(format!(
                "json.corrupt-{}",
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map(|d| d.as_millis())
                    .unwrap_or(0)
            ));
            tracing::warn!(
                file = %path.display(),
                moved_to = %aside.display(),
                "moving an unreadable scenario file aside before replacing it"
            );
            fs::rename(&path, &aside)?;
        }
        let body = serde_json::to_vec_pretty(&Stored {
            format: FORMAT,
            id: scenario.id.clone(),
            spec: scenario.spec.clone(),
        })
        .map_err(io::Error::other)?;
        let tmp = self.dir.join(format!(
            ".{}.{}.tmp",
            scenario.id,
            uuid::Uuid::new_v4().simple()
        ));
        let result = (|| {
            let mut f = File::create(&tmp)?;
            f.write_all(&body)?;
            f.sync_all()?;
            fs::rename(&tmp, &path)?;
            self.sync_dir()
        })();
        if result.is_err() {
            let _ = fs::remove_file(&tmp);
        }
        result
    }

    /// Removes a scenario durably. Blocking I/O. Missing files are fine.
    pub fn remove(&self, id: &str) -> io::Result<()> {
        match fs::remove_file(self.path(id)?) {
            Ok(()) => self.sync_dir(),
            Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
            Err(e) => Err(e),
        }
    }

    fn sync_dir(&self) -> io::Result<()> {
        File::open(&self.dir)?.sync_all()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::paper_spec;

    fn tempdir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!(
            "vigil-store-{name}-{}",
            uuid::Uuid::new_v4().simple()
        ));
        fs::create_dir_all(&d).expect("temp dir");
        d
    }

    #[test]
    fn saves_loads_and_removes() {
        let dir = tempdir("roundtrip");
        let (store, loaded) = Store::open(&dir).expect("open");
        assert!(loaded.is_empty());
        let s = Scenario::new(paper_spec(12.0)).expect("valid");
        store.save(&s).expect("save");
        let (_, loaded) = Store::open(&dir).expect("reopen");
        assert_eq!(loaded.len(), 1);
        assert_eq!(loaded[0].id, s.id);
        store.remove(&s.id).expect("remove");
        assert!(Store::open(&dir).expect("reopen").1.is_empty());
        fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn corrupt_files_are_skipped_and_kept() {
        let dir = tempdir("corrupt");
        let s = Scenario::new(paper_spec(12.0)).expect("valid");
        let (store, _) = Store::open(&dir).expect("open");
        store.save(&s).expect("save");
        fs::write(
            dir.join("s-0000000000000000.json"),
            b"{\"format\":1,\"id\":",
        )
        .expect("write");
        fs::write(dir.join("foreign.json"), b"[1,2,3]").expect("write");
        let (_, loaded) = Store::open(&dir).expect("reopen");
        assert_eq!(loaded.len(), 1);
        // Skipped, not deleted.
        assert!(dir.join("foreign.json").exists());
        // Saving over a corrupt file moves it aside first.
        let path = dir.join(format!("{}.json", s.id));
        fs::write(&path, b"garbage").expect("write");
        store.save(&s).expect("save");
        let aside = fs::read_dir(&dir)
            .expect("list")
            .filter_map(|e| e.ok())
            .any(|e| e.file_name().to_string_lossy().contains(".corrupt-"));
        assert!(aside);
        assert_eq!(Store::open(&dir).expect("reopen").1.len(), 1);
        fs::remove_dir_all(dir).ok();
    }
}
