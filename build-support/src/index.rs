//! The plugin index: a cached plugin found from what its source was generated
//! from, without generating the source or starting rustc.
//!
//! A library in the cache is named by the hash of its source, the compiler's
//! `rustc -vV`, its target description (`rustc --print cfg`) and its flags
//! ([`crate::build_plugin`]). Finding it that way on every run costs the
//! caller's source generation (for a vehicle, tens of milliseconds of
//! symbolic derivation and formatting) and two rustc processes (tens of
//! milliseconds more), each time, for an answer that rarely changes. The
//! index remembers the answer under a key that needs neither:
//!
//! - the caller's **input digest**, a hash of everything the source is
//!   generated from, including a digest of the generator's own code (the
//!   code generator computes it);
//! - the build flags and ABI version;
//! - the **compiler as found**, without running it: the program that
//!   [`crate::find_rustc`] would pick (its path, size and modification time)
//!   and, because a rustup proxy picks its toolchain from them, `RUSTC`,
//!   `RUSTUP_TOOLCHAIN`, `RUSTUP_HOME`, rustup's `settings.toml` and the
//!   nearest `rust-toolchain(.toml)` above the working directory;
//! - this machine's **CPU features** (x86-64: the feature words of `cpuid`
//!   and the OS-enabled register state), which `-C target-cpu=native` builds
//!   for.
//!
//! An entry (`index/<key>`) records the library's file name, the rustc that
//! built it (path and `rustc -vV`) and that compiler's driver library
//! (`<sysroot>/lib/librustc_driver-<hash>.so`, whose name changes with every
//! compiler release). It is used only if the driver file still exists (a
//! toolchain updated in place under the same name is noticed) and the
//! library matches its recorded size and BLAKE3 digest; otherwise the caller
//! takes the full path, which rebuilds what is needed and records a fresh
//! entry. On platforms other than x86-64 native builds are not indexed.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::cache::{self, write_atomic};
use crate::{BuildOptions, BuildOutput, Rustc, resolve_cache_dir};

/// First line of every entry; the number is the layout's version.
const MAGIC: &str = "railmbs plugin index 1";

/// The cached plugin of `input_digest` built with `options`, if the index
/// knows it and it is still valid; `None` sends the caller the full way
/// ([`crate::build_plugin`], then [`record`]).
pub fn lookup(input_digest: &str, options: &BuildOptions) -> Option<BuildOutput> {
    let cache = cache_dir(options)?;
    let key = index_key(input_digest, options)?;
    let text = std::fs::read_to_string(cache.join("index").join(&key)).ok()?;
    let entry = Entry::parse(&text)?;
    if !Path::new(&entry.driver).is_file() {
        return None;
    }
    let path = cache.join(&entry.library);
    cache::verify_digest(&path).ok()?;
    let hash = entry
        .library
        .strip_prefix(std::env::consts::DLL_PREFIX)?
        .strip_suffix(std::env::consts::DLL_SUFFIX)?
        .strip_prefix("railmbs_plugin_")?
        .to_owned();
    Some(BuildOutput {
        path,
        hash,
        cache_hit: true,
        compile_time: None,
        rustc: Rustc {
            path: PathBuf::from(entry.rustc),
            version: entry.version,
        },
        rebuilt_damaged: None,
    })
}

/// Records `built` (a result of [`crate::build_plugin`] with `options`) as
/// the plugin of `input_digest`. Best effort: a cache that cannot be
/// written, or a compiler whose driver library cannot be found, only means
/// the next run takes the full way again.
pub fn record(input_digest: &str, options: &BuildOptions, built: &BuildOutput) {
    let (Some(cache), Some(key)) = (cache_dir(options), index_key(input_digest, options)) else {
        return;
    };
    let Some(library) = built.path.file_name().and_then(OsStr::to_str) else {
        return;
    };
    let Some(driver) = driver_library(&built.rustc.path) else {
        return;
    };
    let entry = Entry {
        library: library.to_owned(),
        rustc: built.rustc.path.to_string_lossy().into_owned(),
        driver: driver.to_string_lossy().into_owned(),
        version: built.rustc.version.clone(),
    };
    let Some(text) = entry.to_text() else {
        return;
    };
    let dir = cache.join("index");
    if cache::create_dir_all(&dir).is_ok() {
        let _ = write_atomic(&dir.join(key), text.as_bytes());
    }
}

fn cache_dir(options: &BuildOptions) -> Option<PathBuf> {
    let dir = resolve_cache_dir(options.cache_dir.as_deref()).ok()?;
    std::path::absolute(dir).ok()
}

/// One index entry.
#[derive(Debug, PartialEq)]
struct Entry {
    /// File name of the library in the cache directory.
    library: String,
    /// The rustc that built it.
    rustc: String,
    /// That compiler's driver library.
    driver: String,
    /// Its `rustc -vV`.
    version: String,
}

impl Entry {
    /// The entry as text; `None` if a field would not read back.
    fn to_text(&self) -> Option<String> {
        let one_line = [&self.library, &self.rustc, &self.driver];
        if one_line.iter().any(|f| f.contains('\n')) {
            return None;
        }
        Some(format!(
            "{MAGIC}\nlibrary {}\nrustc {}\ndriver {}\n{}",
            self.library, self.rustc, self.driver, self.version
        ))
    }

    fn parse(text: &str) -> Option<Entry> {
        let mut lines = text.splitn(5, '\n');
        if lines.next()? != MAGIC {
            return None;
        }
        let mut field = |name: &str| {
            lines
                .next()?
                .strip_prefix(name)?
                .strip_prefix(' ')
                .map(str::to_owned)
        };
        let library = field("library")?;
        let rustc = field("rustc")?;
        let driver = field("driver")?;
        let version = lines.next()?.to_owned();
        version.starts_with("rustc ").then_some(Entry {
            library,
            rustc,
            driver,
            version,
        })
    }
}

/// The index key of `input_digest` with `options` on this machine, or `None`
/// where the index cannot tell machines apart (native builds off x86-64) or
/// no compiler is found.
fn index_key(input_digest: &str, options: &BuildOptions) -> Option<String> {
    let mut h = blake3::Hasher::new();
    let mut field = |bytes: &[u8]| {
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    };
    field(MAGIC.as_bytes());
    field(input_digest.as_bytes());
    field(&options.abi_version.to_le_bytes());
    for flag in options.flags() {
        field(flag.as_bytes());
    }
    field(compiler_fingerprint(options)?.as_bytes());
    let native = options
        .extra_flags
        .iter()
        .any(|f| f.contains("target-cpu") || f.contains("target-feature"));
    match cpu_fingerprint() {
        Some(cpu) => field(cpu.as_bytes()),
        None if native => return None,
        None => {}
    }
    Some(h.finalize().to_hex().to_string())
}

/// What decides which compiler [`crate::find_rustc`] would run, read
/// without running it.
fn compiler_fingerprint(options: &BuildOptions) -> Option<String> {
    let program = match (&options.rustc, std::env::var_os("RUSTC")) {
        (Some(p), _) => p.clone(),
        (None, Some(v)) if !v.is_empty() => PathBuf::from(v),
        _ => crate::rustc::search_path(std::env::var_os("PATH"))?,
    };
    let mut parts = vec![format!("program {}", program.display())];
    let meta = std::fs::metadata(&program).ok()?;
    let modified = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    parts.push(format!("size {} modified {modified}", meta.len()));
    for var in ["RUSTC", "RUSTUP_TOOLCHAIN", "RUSTUP_HOME"] {
        parts.push(format!("{var}={:?}", std::env::var_os(var)));
    }
    let rustup_home = std::env::var_os("RUSTUP_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".rustup")));
    if let Some(settings) = rustup_home.map(|h| h.join("settings.toml")) {
        parts.push(format!("settings {:?}", std::fs::read(settings).ok()));
    }
    if let Ok(mut dir) = std::env::current_dir() {
        loop {
            for name in ["rust-toolchain.toml", "rust-toolchain"] {
                if let Ok(text) = std::fs::read(dir.join(name)) {
                    parts.push(format!("{} {text:?}", dir.join(name).display()));
                }
            }
            if !dir.pop() {
                break;
            }
        }
    }
    Some(parts.join("\n"))
}

/// The CPU features a `-C target-cpu=native` build depends on: `cpuid`'s
/// feature words (leaves 1, 7 and 0x80000001, and 0xD.1) and the register
/// state the OS enables (XCR0). Not the model or stepping bits, nor the
/// APIC id, which differ between cores.
#[cfg(target_arch = "x86_64")]
fn cpu_fingerprint() -> Option<String> {
    use std::arch::x86_64::{__cpuid, __cpuid_count, _xgetbv};
    // SAFETY: cpuid exists on every x86-64 CPU; xgetbv is executed only when
    // cpuid says the OS enabled it (OSXSAVE).
    unsafe {
        let max = __cpuid(0).eax;
        let max_ext = __cpuid(0x8000_0000).eax;
        let l1 = __cpuid(1);
        let l7 = if max >= 7 {
            __cpuid_count(7, 0)
        } else {
            __cpuid(0)
        };
        let xsave = if max >= 0xd {
            __cpuid_count(0xd, 1).eax
        } else {
            0
        };
        let ext = if max_ext >= 0x8000_0001 {
            __cpuid(0x8000_0001)
        } else {
            __cpuid(0)
        };
        let osxsave = l1.ecx & (1 << 27) != 0;
        let xcr0 = if osxsave { _xgetbv(0) } else { 0 };
        Some(format!(
            "x86_64 {:08x} {:08x} {:08x} {:08x} {:08x} {:08x} {:08x} {:08x} {xcr0:016x}",
            l1.ecx, l1.edx, l7.ebx, l7.ecx, l7.edx, xsave, ext.ecx, ext.edx
        ))
    }
}

/// Off x86-64 the CPU is not told apart: native builds are not indexed.
#[cfg(not(target_arch = "x86_64"))]
fn cpu_fingerprint() -> Option<String> {
    None
}

/// The driver library of the compiler `rustc` (`<sysroot>/lib/
/// librustc_driver-<hash>.so`, `.dylib` on macOS, `bin/rustc_driver-*.dll`
/// on Windows): its name changes with every release, so its presence says
/// that the toolchain was not replaced in place.
fn driver_library(rustc: &Path) -> Option<PathBuf> {
    let out = Command::new(rustc)
        .args(["--print", "sysroot"])
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let sysroot = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
    let dir = sysroot.join(if cfg!(windows) { "bin" } else { "lib" });
    let prefix = format!("{}rustc_driver-", std::env::consts::DLL_PREFIX);
    std::fs::read_dir(dir)
        .ok()?
        .flatten()
        .map(|e| e.path())
        .find(|p| {
            p.file_name().and_then(OsStr::to_str).is_some_and(|n| {
                n.starts_with(&prefix) && n.ends_with(std::env::consts::DLL_SUFFIX)
            })
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_read_back_and_malformed_ones_are_refused() {
        let e = Entry {
            library: "librailmbs_plugin_ab.so".into(),
            rustc: "/usr/bin/rustc".into(),
            driver: "/x/lib/librustc_driver-1.so".into(),
            version: "rustc 1.95.0\nhost: x86_64\n".into(),
        };
        let text = e.to_text().unwrap();
        assert_eq!(Entry::parse(&text), Some(e));
        assert_eq!(Entry::parse(&text.replace("index 1", "index 2")), None);
        assert_eq!(Entry::parse(&text.replace("rustc 1.95", "cc 1.95")), None);
        assert_eq!(Entry::parse(&text[..30]), None);
        let bad = Entry {
            library: "a\nb".into(),
            rustc: String::new(),
            driver: String::new(),
            version: String::new(),
        };
        assert_eq!(bad.to_text(), None);
    }
}
