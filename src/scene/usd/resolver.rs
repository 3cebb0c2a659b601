//! The asset resolver every layer is read through: openusd's default resolver, with each
//! layer checked before openusd parses it. A layer must be a regular file (a FIFO or
//! `/dev/zero` would be read forever), a text layer must not nest deeper than its parser's
//! recursion allows (`usda_check.rs`), and a crate file must pass `usdc_check.rs`.

use openusd::ar::{self, Asset, DefaultResolver, ResolvedPath, Resolver};
use std::io;
use std::path::Path;
use std::sync::{Arc, Mutex};

use super::{usda_check, usdc_check};
use crate::desc::ContentHash;
use crate::error::Reason;

/// [`DefaultResolver`] with checked layers.
#[derive(Default)]
pub(super) struct CheckedResolver {
    inner: DefaultResolver,
    /// The hash of the bytes of the layers read so far, shared with the opener.
    digest: Arc<Mutex<ContentHash>>,
}

impl Resolver for CheckedResolver {
    fn create_identifier(&self, asset_path: &str, anchor: Option<&ResolvedPath>) -> String {
        self.inner.create_identifier(asset_path, anchor)
    }

    fn resolve(&self, asset_path: &str) -> Option<ResolvedPath> {
        self.inner.resolve(asset_path)
    }

    fn resolve_for_new_asset(&self, asset_path: &str) -> Option<ResolvedPath> {
        self.inner.resolve_for_new_asset(asset_path)
    }

    fn open_asset(&self, resolved: &ResolvedPath) -> io::Result<Box<dyn Asset>> {
        let packaged = resolved.to_str().is_some_and(ar::is_package_relative_path);
        if !packaged {
            regular_file(resolved).map_err(io::Error::other)?;
        }
        let bytes = self.inner.open_asset(resolved)?.read_all()?;
        check_layer(&bytes).map_err(io::Error::other)?;
        if let Ok(mut d) = self.digest.lock() {
            d.add(&bytes);
        }
        if !packaged && bytes.starts_with(ZIP_MAGIC) {
            self.check_package_root(resolved, &bytes)?;
        }
        Ok(Box::new(io::Cursor::new(bytes)))
    }

    fn get_extension<'a>(&self, asset_path: &'a str) -> &'a str {
        self.inner.get_extension(asset_path)
    }

    fn identity(&self) -> String {
        self.inner.identity()
    }
}

/// The first bytes of a zip archive (a `.usdz` package).
const ZIP_MAGIC: &[u8] = b"PK\x03\x04";

impl CheckedResolver {
    /// A resolver that folds every layer it opens into `digest`.
    pub(super) fn recording(digest: Arc<Mutex<ContentHash>>) -> CheckedResolver {
        CheckedResolver {
            inner: DefaultResolver::default(),
            digest,
        }
    }

    /// A package's root layer is read by openusd straight from the archive, without coming
    /// back through [`Resolver::open_asset`], so it is checked here.
    fn check_package_root(&self, package: &ResolvedPath, bytes: &[u8]) -> io::Result<()> {
        let archive = openusd::usdz::Archive::from_reader(io::Cursor::new(bytes));
        let Some(name) = archive.ok().and_then(|a| a.first_layer_name()) else {
            return Ok(()); // openusd reports a bad archive itself
        };
        let Some(package) = package.to_str() else {
            return Ok(());
        };
        let inner = ResolvedPath::new(ar::join_package_relative_path(package, &name));
        let layer = self.inner.open_asset(&inner)?.read_all()?;
        check_layer(&layer).map_err(|e| io::Error::other(format!("{name}: {e}")))
    }
}

/// Fails unless `path` names a regular file (after following symbolic links).
fn regular_file(path: &Path) -> Reason<()> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => Ok(()),
        Ok(_) => Err(format!("{} is not a regular file", path.display())),
        Err(e) => Err(format!("{}: {e}", path.display())),
    }
}

/// The checks of a layer's bytes, by its content.
pub(super) fn check_layer(bytes: &[u8]) -> Reason<()> {
    if usda_check::is_text(bytes) {
        usda_check::check(bytes)
    } else if usdc_check::is_crate(bytes) {
        usdc_check::check(bytes).map_err(|e| format!("corrupt crate file: {e}"))
    } else {
        Ok(())
    }
}
