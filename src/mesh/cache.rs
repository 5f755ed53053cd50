//! A cache of the meshes gmsh made, so that a run of the same `.geo` script with the same
//! parameters and size factor (a sweep's jobs, a resumed or repeated run, a study's levels
//! run again) reads the mesh instead of meshing it again — gmsh and its element-count probes
//! are most of the mesh phase of a large model.
//!
//! An entry is two files in the cache folder: `<slot>.msh`, the mesh, and `<slot>.key`, the
//! whole text the mesh was made from (a format line, gmsh's version, the size factor's and
//! every parameter's bits, the script's text), followed by the mesh's length and CRC-32. The
//! slot is a hash of that text; an entry is used only when its key text equals the request
//! *exactly* and the mesh's length and checksum match, so neither a hash collision nor a
//! damaged file can pass for a mesh. Entries are written to temporary files and renamed,
//! the key last, so concurrent runs (a sweep's jobs) see whole entries or none.
//!
//! Size: the cache holds at most its limit ([`DEFAULT_LIMIT_MB`] MiB unless
//! `ASPERITY_MESH_CACHE_MB` says otherwise); after each store the least recently used
//! entries are removed until it fits, and a mesh larger than the limit is not stored. The
//! folder is `ASPERITY_MESH_CACHE` if set and not empty (`off` turns the cache off), else
//! `$XDG_CACHE_HOME/asperity/meshes` or `~/.cache/asperity/meshes`. Only files named like
//! entries are ever removed there.
//!
//! Scripts that read other files (`Include`, `Merge`) are not cached: the key would not
//! cover what they read.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// Cache size limit (MiB) when `ASPERITY_MESH_CACHE_MB` is not set.
pub const DEFAULT_LIMIT_MB: u64 = 2048;

/// First line of every key: changes when what a key covers changes (2: the meshes are binary
/// MSH 4.1, so that the ASCII meshes of earlier versions are made anew and not read slowly).
const KEY_FORMAT: &str = "asperity mesh cache 2";

/// The mesh cache: its folder and size limit.
#[derive(Clone, Debug)]
pub struct MeshCache {
    dir: PathBuf,
    limit: u64,
}

/// What a cached mesh was made from (see the module docs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CacheKey {
    text: String,
}

impl CacheKey {
    /// The key of `script` (the `.geo` text) meshed by gmsh `gmsh_version` at size factor
    /// `size` with `parameters`, or `None` when the script reads other files.
    pub fn new(
        script: &str,
        gmsh_version: &str,
        size: f64,
        parameters: &[(String, f64)],
    ) -> Option<Self> {
        let reads_files = script.lines().any(|line| {
            let line = line.trim_start();
            line.starts_with("Include") || line.starts_with("Merge")
        });
        if reads_files {
            return None;
        }
        let mut text = format!(
            "{KEY_FORMAT}\ngmsh {}\nsize {:016x}\n",
            gmsh_version.trim(),
            size.to_bits()
        );
        for (name, value) in parameters {
            text.push_str(&format!("parameter {name} {:016x}\n", value.to_bits()));
        }
        text.push_str(&format!("script {}\n{script}", script.len()));
        Some(Self { text })
    }

    /// The entry's file stem: a hash of the key (collisions are harmless: the key text is
    /// compared in full).
    fn slot(&self) -> String {
        let bytes = self.text.as_bytes();
        let half = bytes.len() / 2;
        format!(
            "{:08x}{:08x}{:08x}",
            crc32fast::hash(bytes),
            crc32fast::hash(&bytes[..half]),
            crc32fast::hash(&bytes[half..])
        )
    }
}

impl MeshCache {
    /// The cache the environment asks for (see the module docs), or `None` when it is off
    /// or no folder for it is known.
    pub fn from_env() -> Option<Self> {
        let dir = match std::env::var_os("ASPERITY_MESH_CACHE") {
            Some(v) if v == "off" => return None,
            Some(v) if !v.is_empty() => PathBuf::from(v),
            _ => std::env::var_os("XDG_CACHE_HOME")
                .filter(|v| !v.is_empty())
                .map(PathBuf::from)
                .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?
                .join("asperity")
                .join("meshes"),
        };
        let limit_mb = match std::env::var("ASPERITY_MESH_CACHE_MB") {
            Ok(v) => v.trim().parse::<u64>().unwrap_or_else(|_| {
                tracing::warn!(
                    "ASPERITY_MESH_CACHE_MB = {v:?} is not a whole number of MiB; using \
                     {DEFAULT_LIMIT_MB}"
                );
                DEFAULT_LIMIT_MB
            }),
            Err(_) => DEFAULT_LIMIT_MB,
        };
        Some(Self::new(dir, limit_mb.saturating_mul(1 << 20)))
    }

    /// A cache in `dir` holding at most `limit` bytes.
    pub fn new(dir: PathBuf, limit: u64) -> Self {
        Self { dir, limit }
    }

    fn paths(&self, key: &CacheKey) -> (PathBuf, PathBuf) {
        let slot = key.slot();
        (
            self.dir.join(format!("{slot}.msh")),
            self.dir.join(format!("{slot}.key")),
        )
    }

    /// Copies the mesh cached for `key` to `out` and returns true, or returns false when
    /// there is no valid entry (a damaged one is removed).
    pub fn fetch(&self, key: &CacheKey, out: &Path) -> bool {
        let (mesh, key_file) = self.paths(key);
        let Ok(stored) = std::fs::read_to_string(&key_file) else {
            return false;
        };
        let Some((text, check)) = stored.rsplit_once("\nmesh ") else {
            return false;
        };
        if text != key.text {
            return false;
        }
        let Ok(bytes) = std::fs::read(&mesh) else {
            return false;
        };
        if check != checksum(&bytes) {
            tracing::warn!(
                "mesh cache: {} is damaged (length or checksum), meshing again",
                mesh.display()
            );
            let _ = std::fs::remove_file(&key_file);
            return false;
        }
        if let Err(e) = std::fs::write(out, &bytes) {
            tracing::warn!("mesh cache: cannot copy to {}: {e}", out.display());
            return false;
        }
        // Least recently *used* goes first when the cache is trimmed.
        let _ = std::fs::File::options()
            .append(true)
            .open(&key_file)
            .and_then(|f| f.set_modified(SystemTime::now()));
        true
    }

    /// Stores the mesh file `mesh` for `key` (best effort: a failure is logged, the run goes
    /// on), then trims the cache to its limit.
    pub fn store(&self, key: &CacheKey, mesh: &Path) {
        if let Err(e) = self.try_store(key, mesh) {
            tracing::warn!("mesh cache: cannot store in {}: {e}", self.dir.display());
        }
    }

    fn try_store(&self, key: &CacheKey, mesh: &Path) -> std::io::Result<()> {
        let bytes = std::fs::read(mesh)?;
        if bytes.len() as u64 > self.limit {
            return Ok(());
        }
        std::fs::create_dir_all(&self.dir)?;
        let (mesh_path, key_path) = self.paths(key);
        let write = |path: &Path, content: &[u8]| -> std::io::Result<()> {
            let mut tmp = tempfile::NamedTempFile::new_in(&self.dir)?;
            std::io::Write::write_all(&mut tmp, content)?;
            tmp.persist(path).map_err(|e| e.error)?;
            Ok(())
        };
        // The key last: a key names a complete mesh.
        let _ = std::fs::remove_file(&key_path);
        write(&mesh_path, &bytes)?;
        let key_text = format!("{}\nmesh {}", key.text, checksum(&bytes));
        write(&key_path, key_text.as_bytes())?;
        self.trim();
        Ok(())
    }

    /// Removes the least recently used entries until the cache holds at most its limit.
    fn trim(&self) {
        let Ok(dir) = std::fs::read_dir(&self.dir) else {
            return;
        };
        let mut entries: Vec<(SystemTime, u64, PathBuf)> = dir
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .filter(|p| is_entry_name(p, "key"))
            .filter_map(|key| {
                let used = std::fs::metadata(&key).and_then(|m| m.modified()).ok()?;
                let mesh = key.with_extension("msh");
                let size = std::fs::metadata(&mesh).map_or(0, |m| m.len());
                Some((used, size, key))
            })
            .collect();
        let mut total: u64 = entries.iter().map(|e| e.1).sum();
        entries.sort();
        for (_, size, key) in entries {
            if total <= self.limit {
                break;
            }
            let _ = std::fs::remove_file(&key);
            let _ = std::fs::remove_file(key.with_extension("msh"));
            total -= size;
        }
    }
}

/// The length and CRC-32 of a mesh file's bytes, as written after a key.
fn checksum(bytes: &[u8]) -> String {
    format!("{} {:08x}", bytes.len(), crc32fast::hash(bytes))
}

/// Whether `path` is named like a cache entry's file (24 hex digits and `extension`): the
/// only files [`MeshCache::trim`] removes.
fn is_entry_name(path: &Path, extension: &str) -> bool {
    path.extension().is_some_and(|e| e == extension)
        && path
            .file_stem()
            .and_then(|s| s.to_str())
            .is_some_and(|s| s.len() == 24 && s.bytes().all(|b| b.is_ascii_hexdigit()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(script: &str, size: f64) -> CacheKey {
        CacheKey::new(script, "4.13.1", size, &[("h".into(), 0.5)]).unwrap()
    }

    #[test]
    fn a_stored_mesh_comes_back_only_for_the_same_key() {
        let dir = tempfile::tempdir().unwrap();
        let cache = MeshCache::new(dir.path().join("cache"), 1 << 20);
        let mesh = dir.path().join("a.msh");
        std::fs::write(&mesh, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n").unwrap();
        let out = dir.path().join("out.msh");
        assert!(!cache.fetch(&key("Point(1) = {0,0,0};", 1.0), &out));
        cache.store(&key("Point(1) = {0,0,0};", 1.0), &mesh);
        assert!(cache.fetch(&key("Point(1) = {0,0,0};", 1.0), &out));
        assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&mesh).unwrap());
        // Another size, parameter value, script or gmsh: a miss.
        assert!(!cache.fetch(&key("Point(1) = {0,0,0};", 0.5), &out));
        assert!(!cache.fetch(&key("Point(1) = {1,0,0};", 1.0), &out));
        let other = CacheKey::new("Point(1) = {0,0,0};", "4.13.1", 1.0, &[("h".into(), 0.25)]);
        assert!(!cache.fetch(&other.unwrap(), &out));
        let other = CacheKey::new("Point(1) = {0,0,0};", "4.11.0", 1.0, &[("h".into(), 0.5)]);
        assert!(!cache.fetch(&other.unwrap(), &out));
    }

    #[test]
    fn a_damaged_entry_is_not_used() {
        let dir = tempfile::tempdir().unwrap();
        let cache = MeshCache::new(dir.path().to_path_buf(), 1 << 20);
        let mesh = dir.path().join("a.msh");
        std::fs::write(&mesh, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n").unwrap();
        let k = key("x = 1;", 1.0);
        cache.store(&k, &mesh);
        let (cached, _) = cache.paths(&k);
        std::fs::write(&cached, "$MeshFormat\n4.1 0 9\n$EndMeshFormat\n").unwrap();
        assert!(!cache.fetch(&k, &dir.path().join("out.msh")));
    }

    #[test]
    fn the_cache_keeps_to_its_limit_dropping_the_least_recently_used() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("cache");
        let cache = MeshCache::new(root.clone(), 2500);
        let mesh = dir.path().join("a.msh");
        std::fs::write(&mesh, vec![b'x'; 1000]).unwrap();
        let bystander = root.join("notes.txt");
        let out = dir.path().join("out.msh");
        for i in 0..2 {
            cache.store(&key(&format!("x = {i};"), 1.0), &mesh);
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        std::fs::write(&bystander, "mine").unwrap();
        assert!(
            cache.fetch(&key("x = 0;", 1.0), &out),
            "used: now the most recent"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
        cache.store(&key("x = 2;", 1.0), &mesh);
        assert!(cache.fetch(&key("x = 0;", 1.0), &out));
        assert!(
            !cache.fetch(&key("x = 1;", 1.0), &out),
            "least recently used: dropped"
        );
        assert!(cache.fetch(&key("x = 2;", 1.0), &out));
        assert!(bystander.exists(), "only entries are removed");
        // A mesh larger than the limit is not stored at all.
        std::fs::write(&mesh, vec![b'x'; 3000]).unwrap();
        cache.store(&key("x = 3;", 1.0), &mesh);
        assert!(!cache.fetch(&key("x = 3;", 1.0), &out));
    }

    #[test]
    fn scripts_that_read_other_files_are_not_keyed() {
        assert!(CacheKey::new("Include \"part.geo\";", "4", 1.0, &[]).is_none());
        assert!(CacheKey::new("  Merge \"a.step\";", "4", 1.0, &[]).is_none());
    }
}
