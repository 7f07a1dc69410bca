//! Where a cache's segments, leases and run marks live when they are not in a directory: the
//! storage backend of a cache in an object store (`--cache s3://BUCKET/PREFIX`,
//! docs/cache-in-a-bucket.md).
//!
//! A cache directory is the backend of every cache today and stays exactly as it was: `Store`
//! without a [`Remote`] reads and writes its directory alone. A store with a remote keeps the
//! remote as the one truth and its directory as a **read-through copy** of it:
//!
//! - the segments are the remote's objects named `seg-*.parquet` under the prefix; a listing is the
//!   remote's listing, and a segment listed there and not yet copied is fetched whole (its length
//!   checked against the listing) and written atomically into the directory before it is read. A
//!   segment is written once under a name no other writer picks and never changed, so a copy is
//!   never stale: reads of a bucket the directory already holds cost one listing;
//! - a new segment is uploaded with one create-only PUT under its final name (a partial upload is
//!   no object at all, so it is never listed), then copied into the directory;
//! - leases and run marks are small objects made by create-only PUTs ([`crate::cache::leases`]);
//! - what a report derives (`_derived/`) stays in the directory: it is this machine's memo.
//!
//! The object store client and its async runtime live in [`bucket`] (the `s3` feature); the rest
//! of qsweep sees only the synchronous [`Remote`] trait. A directory can serve as a remote too
//! ([`dir::DirRemote`]): the tests of the rules above run on it without a server.

#[cfg(feature = "s3")]
pub mod bucket;
pub mod dir;
pub mod transfer;

use crate::error::user_error;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::SystemTime;

/// An object as a listing shows it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Listed {
    /// Its name below the cache's prefix, e.g. `seg-….parquet` or `_leases/<key>`.
    pub name: String,
    /// Its length in bytes.
    pub size: u64,
    /// When the store last wrote it, by the store's own clock.
    pub modified: SystemTime,
}

/// The operations a cache needs of an object store, by name below the cache's prefix. Every one
/// is a single request; none needs a lock or a shared clock beyond the store's own.
pub trait Remote: Send + Sync + std::fmt::Debug {
    /// The cache's address as the user gave it (`s3://bucket/prefix`), for messages.
    fn url(&self) -> &str;
    /// The objects directly in the folder `dir` (`""` for the top, `"_leases"`), not below it.
    fn list(&self, dir: &str) -> anyhow::Result<Vec<Listed>>;
    /// An object's bytes, `None` when there is no such object.
    fn get(&self, name: &str) -> anyhow::Result<Option<Vec<u8>>>;
    /// An object's listing entry, `None` when there is no such object.
    fn head(&self, name: &str) -> anyhow::Result<Option<Listed>>;
    /// Create the object only if no object has that name (one conditional PUT,
    /// `If-None-Match: *`): `true` when this call made it, `false` when it existed.
    fn create(&self, name: &str, body: &[u8]) -> anyhow::Result<bool>;
    /// Write the object whatever is there (a run mark's heartbeat).
    fn put(&self, name: &str, body: &[u8]) -> anyhow::Result<()>;
    /// Remove the object; an object already gone is no error.
    fn delete(&self, name: &str) -> anyhow::Result<()>;
    /// [`Remote::create`] of each object, answered in order; a store that can sends them at once
    /// (a batch of leases costs the time of one request, not of one per key).
    fn create_each(&self, objects: &[(String, Vec<u8>)]) -> Vec<anyhow::Result<bool>> {
        objects.iter().map(|(name, body)| self.create(name, body)).collect()
    }
    /// [`Remote::delete`] of each object; a store that can removes them in one request (S3's
    /// multi-object delete, up to 1000 a request).
    fn delete_each(&self, names: &[String]) -> anyhow::Result<()> {
        names.iter().try_for_each(|n| self.delete(n))
    }
}

/// A shared handle on a remote.
pub type RemoteRef = Arc<dyn Remote>;

/// The scheme of a cache in an S3-compatible bucket.
pub const S3_SCHEME: &str = "s3://";

/// Whether `cache` (as given to `--cache` or `QSWEEP_CACHE`) names a bucket, not a directory.
pub fn is_remote(cache: &str) -> bool {
    cache.starts_with(S3_SCHEME)
}

/// A bucket cache's address: its bucket and its prefix (no leading or trailing `/`, may be empty).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Address {
    /// The bucket.
    pub bucket: String,
    /// The folder inside it that holds the cache.
    pub prefix: String,
}

impl Address {
    /// Parse `s3://BUCKET[/PREFIX]`; a usage error naming the fix otherwise.
    pub fn parse(url: &str) -> anyhow::Result<Self> {
        let rest = url.strip_prefix(S3_SCHEME).ok_or_else(|| {
            user_error(format!("cache {url}: only s3://BUCKET/PREFIX addresses name a bucket"))
        })?;
        let (bucket, prefix) = rest.split_once('/').unwrap_or((rest, ""));
        let ok = !bucket.is_empty()
            && bucket.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '.');
        if !ok {
            return Err(user_error(format!(
                "cache {url}: `{bucket}` is not a bucket name (lower-case letters, digits, `-` and `.`); \
                 write s3://BUCKET/PREFIX"
            )));
        }
        let prefix = prefix.trim_matches('/').to_string();
        if prefix.split('/').any(|p| p == "." || p == "..") || prefix.contains("//") {
            return Err(user_error(format!(
                "cache {url}: the prefix `{prefix}` has an empty, `.` or `..` part"
            )));
        }
        Ok(Self { bucket: bucket.to_string(), prefix })
    }

    /// The address as `s3://bucket/prefix`.
    pub fn url(&self) -> String {
        if self.prefix.is_empty() {
            format!("{S3_SCHEME}{}", self.bucket)
        } else {
            format!("{S3_SCHEME}{}/{}", self.bucket, self.prefix)
        }
    }
}

/// The environment variable naming the folder of the read-through copies of bucket caches.
pub const COPY_ENV: &str = "QSWEEP_BUCKET_COPIES";

/// Where the read-through copy of the cache at `address` lives on this machine:
/// `$QSWEEP_BUCKET_COPIES/<bucket>/<prefix>`, by default under `$XDG_CACHE_HOME/qsweep/buckets`
/// (`~/.cache/qsweep/buckets`). One folder per address, so two caches never share a copy.
pub fn copy_dir(address: &Address) -> PathBuf {
    let root = std::env::var_os(COPY_ENV)
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("XDG_CACHE_HOME")
                .filter(|v| !v.is_empty())
                .map(|d| PathBuf::from(d).join("qsweep/buckets"))
        })
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/qsweep/buckets")))
        .unwrap_or_else(|| std::env::temp_dir().join("qsweep-buckets"));
    let mut dir = root.join(&address.bucket);
    if !address.prefix.is_empty() {
        dir = dir.join(&address.prefix);
    }
    dir
}

/// Connect to the bucket of `address` and check that it answers (a missing bucket or refused
/// credentials is a usage error naming the bucket, exit 2); [`crate::cache::Store::open_bucket`]
/// opens the cache in it.
#[cfg(feature = "s3")]
pub fn connect(address: &Address) -> anyhow::Result<RemoteRef> {
    Ok(Arc::new(bucket::Bucket::connect(address)?))
}

/// Without the `s3` feature: a usage error saying how to build a qsweep that has buckets.
#[cfg(not(feature = "s3"))]
pub fn connect(address: &Address) -> anyhow::Result<RemoteRef> {
    Err(user_error(format!(
        "cache {}: this qsweep was built without buckets; build it with `cargo build --release \
         --features s3` (docs/cache-in-a-bucket.md), or give a directory with --cache DIR",
        address.url()
    )))
}

/// The name of the object `name` in the folder `dir` (`""` is the top).
pub fn join(dir: &str, name: &str) -> String {
    if dir.is_empty() {
        name.to_string()
    } else {
        format!("{dir}/{name}")
    }
}

/// The object name of a segment whose copy is at `path`: its file name.
pub fn object_of(path: &Path) -> anyhow::Result<String> {
    path.file_name()
        .and_then(|n| n.to_str())
        .map(str::to_string)
        .ok_or_else(|| anyhow::anyhow!("{} is not a segment", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_address_names_a_bucket_and_a_prefix_and_a_bad_one_says_what_to_write() {
        let a = Address::parse("s3://my-bucket/team/qsweep/").unwrap();
        assert_eq!((a.bucket.as_str(), a.prefix.as_str()), ("my-bucket", "team/qsweep"));
        assert_eq!(a.url(), "s3://my-bucket/team/qsweep");
        assert_eq!(Address::parse("s3://b").unwrap().prefix, "");
        for bad in ["s3://", "s3:///x", "s3://Big/x", "s3://b/a/../c", "s3://b/a//c", "gs://b"] {
            let e = Address::parse(bad).unwrap_err();
            assert!(e.is::<crate::error::UserError>(), "{bad}: {e}");
        }
        assert!(is_remote("s3://b") && !is_remote("cache") && !is_remote("./s3://x"));
    }
}

#[cfg(all(test, not(feature = "s3")))]
mod without_buckets {
    #[test]
    fn a_build_without_the_s3_feature_says_how_to_build_one_with_it() {
        let e = super::connect(&super::Address::parse("s3://my-bucket/x").unwrap()).unwrap_err();
        assert!(e.is::<crate::error::UserError>());
        assert!(format!("{e}").contains("cargo build --release --features s3"), "{e}");
    }
}
