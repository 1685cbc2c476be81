//! Contact tables kept on disk between runs, found by a content hash of
//! everything they are computed from.
//!
//! Building the contact table of a wheelset (a few thousand contact searches
//! over lateral shift and roll, [`ContactTable::new`]) is most of the start-up
//! of a vehicle run: about 0.2 s of CPU for Manchester Vehicle 1, against
//! 0.6 s for its 42 s on track case 1. The table is a pure function of its
//! inputs, so it is cached like the compiled plugins, in the `contact-tables`
//! folder of the plugin cache directory
//! ([`railmbs_build_support::resolve_cache_dir`]: `RAILMBS_CACHE_DIR`, else
//! e.g. `~/.cache/railmbs/plugins`).
//!
//! **Key** ([`TableKey`]): a BLAKE3 hash of the profiles' points as read (their
//! bits, not their file names), the profile settings (smoothing, rail
//! inclination), the wheelset's dimensions, the gauge, the search and table
//! settings, and [`railmbs_wheelrail::SOURCE_DIGEST`], a digest of the contact
//! library's source and compiler: any change to the code that computes a
//! table gives new keys, with no version number to remember.
//!
//! **Entry**: `<key>.table`, holding a magic line, the BLAKE3 digest of the
//! payload and the payload (the table, serialized with postcard: every `f64`
//! by its bits, so a table read back equals the one built, and a run from it
//! writes the same numbers). An entry that is missing, truncated, damaged or
//! unreadable is rebuilt and rewritten (atomically: readers never see half a
//! file). A cache directory that cannot be written only costs the rebuild.

use railmbs_wheelrail::geometry::{ContactTable, SearchSettings, TableSettings};
use railmbs_wheelrail::profile::{ProfilePoints, ProfileSettings};
use std::path::{Path, PathBuf};

/// First bytes of every entry; the number is the entry layout's version.
const MAGIC: &[u8] = b"railmbs contact table 1\n";

/// Folder of the entries inside the plugin cache directory.
const SUBDIR: &str = "contact-tables";

/// The content hash that names a contact table (64 hex digits).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) struct TableKey(String);

/// Everything a contact table is computed from.
pub(crate) struct TableInputs<'a> {
    /// Left and right wheel profiles as read, with their settings.
    pub wheels: [(&'a ProfilePoints, ProfileSettings); 2],
    /// Left and right rail profiles as read, with their settings (the rail
    /// inclination among them).
    pub rails: [(&'a ProfilePoints, ProfileSettings); 2],
    /// Wheel radius, m.
    pub radius: f64,
    /// Flange back distance, m.
    pub flange_back_distance: f64,
    /// Lateral offset of the taping line, m.
    pub taping_offset: f64,
    /// Nominal track gauge, m.
    pub gauge: f64,
    /// Contact search settings.
    pub search: SearchSettings,
    /// Table grid.
    pub table: TableSettings,
}

impl TableInputs<'_> {
    /// The key: BLAKE3 over a canonical byte string of the inputs (floats by
    /// their bits; settings by their `Debug` text, which writes every float
    /// so that it reads back to the same bits).
    pub(crate) fn key(&self) -> TableKey {
        let mut h = blake3::Hasher::new();
        h.update(b"railmbs contact table\0");
        h.update(railmbs_wheelrail::SOURCE_DIGEST.as_bytes());
        let mut profile = |(points, settings): &(&ProfilePoints, ProfileSettings)| {
            h.update(format!("\0{:?}\0{}\0", points.kind, points.points.len()).as_bytes());
            for [u, z] in &points.points {
                h.update(&u.to_bits().to_le_bytes());
                h.update(&z.to_bits().to_le_bytes());
            }
            h.update(format!("{settings:?}").as_bytes());
        };
        self.wheels.iter().chain(&self.rails).for_each(&mut profile);
        for x in [
            self.radius,
            self.flange_back_distance,
            self.taping_offset,
            self.gauge,
        ] {
            h.update(&x.to_bits().to_le_bytes());
        }
        h.update(format!("\0{:?}\0{:?}", self.search, self.table).as_bytes());
        TableKey(h.finalize().to_hex().to_string())
    }
}

/// A folder of cached contact tables.
pub(crate) struct TableCache {
    dir: PathBuf,
}

impl TableCache {
    /// The cache in `dir`.
    pub(crate) fn at(dir: impl Into<PathBuf>) -> TableCache {
        TableCache { dir: dir.into() }
    }

    /// The cache in the plugin cache directory; `None` when there is none
    /// (no `RAILMBS_CACHE_DIR` and no home directory): tables are then built
    /// every run.
    pub(crate) fn default_location() -> Option<TableCache> {
        railmbs_build_support::resolve_cache_dir(None)
            .ok()
            .map(|d| TableCache::at(d.join(SUBDIR)))
    }

    fn entry(&self, key: &TableKey) -> PathBuf {
        self.dir.join(format!("{}.table", key.0))
    }

    /// The table under `key`, read from the cache, or built by `build` and
    /// stored (a failed store is ignored: the cache only saves time).
    pub(crate) fn get_or_build<E>(
        &self,
        key: &TableKey,
        build: impl FnOnce() -> Result<ContactTable, E>,
    ) -> Result<ContactTable, E> {
        let path = self.entry(key);
        if let Ok(table) = read_entry(&path) {
            return Ok(table);
        }
        let table = build()?;
        let _ = write_entry(&path, &table);
        Ok(table)
    }
}

/// Reads and checks one entry; `Err` says why it cannot be used.
pub(crate) fn read_entry(path: &Path) -> Result<ContactTable, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    let rest = bytes
        .strip_prefix(MAGIC)
        .ok_or("not a contact table entry of this layout")?;
    if rest.len() < 32 {
        return Err("truncated".to_owned());
    }
    let (digest, payload) = rest.split_at(32);
    if blake3::hash(payload).as_bytes() != digest {
        return Err("its content differs from its recorded digest".to_owned());
    }
    postcard::from_bytes(payload).map_err(|e| e.to_string())
}

/// Writes one entry atomically, creating the folder.
pub(crate) fn write_entry(path: &Path, table: &ContactTable) -> Result<(), String> {
    let payload = postcard::to_stdvec(table).map_err(|e| e.to_string())?;
    let mut bytes = Vec::with_capacity(MAGIC.len() + 32 + payload.len());
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(blake3::hash(&payload).as_bytes());
    bytes.extend_from_slice(&payload);
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    }
    railmbs_build_support::write_atomic(path, &bytes).map_err(|e| e.to_string())
}
