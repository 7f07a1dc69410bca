//! An S3-compatible bucket as a [`Remote`], through the Arrow project's `object_store` crate (the
//! `s3` feature). The async client runs on a small tokio runtime owned by the [`Bucket`]; every
//! [`Remote`] call blocks on it, so nothing outside this module knows it is async.
//!
//! The client is configured from the standard environment (`AmazonS3Builder::from_env`):
//! `AWS_ENDPOINT_URL` (any S3-compatible server), `AWS_ACCESS_KEY_ID`, `AWS_SECRET_ACCESS_KEY`,
//! `AWS_SESSION_TOKEN`, `AWS_REGION`, and plain http only with `AWS_ALLOW_HTTP=true`. A create-only
//! PUT is `If-None-Match: *` (`PutMode::Create`), which AWS S3, MinIO and Cloudflare R2 answer
//! atomically. Requests that fail on the way (a refused connection, a timeout, a 5xx) are
//! retried with backoff for [`RETRY_ENV`] seconds (60 by default), then the command fails naming
//! the bucket.

use super::{join, Address, Listed, Remote};
use crate::error::user_error;
use object_store::aws::{AmazonS3, AmazonS3Builder, AmazonS3ConfigKey};
use object_store::path::Path as ObjectPath;
use object_store::{
    ClientConfigKey, ObjectStore, ObjectStoreExt, PutMode, PutOptions, PutPayload, RetryConfig,
};
use std::time::Duration;

/// The environment variable bounding how long a failing request is retried, in seconds.
pub const RETRY_ENV: &str = "QSWEEP_S3_RETRY_SECONDS";

/// The environment variable that lets the client look for credentials beyond the environment's
/// keys (an instance role, through the machine's metadata service).
pub const INSTANCE_CREDENTIALS_ENV: &str = "QSWEEP_S3_INSTANCE_CREDENTIALS";

/// A bucket cache's client: the store, the cache's prefix in it, and the runtime it runs on.
#[derive(Debug)]
pub struct Bucket {
    store: AmazonS3,
    prefix: String,
    url: String,
    bucket: String,
    runtime: tokio::runtime::Runtime,
    /// Set by the first request that failed after all its retries: every later request fails at
    /// once with it, so a run whose server went away ends with that error instead of retrying each
    /// lease's release for as long again.
    gone: std::sync::Mutex<Option<String>>,
}

impl Bucket {
    /// Connect to the bucket of `address` and check that it answers with one listing: a bucket
    /// that does not exist, or refuses the credentials, is a usage error naming it.
    pub fn connect(address: &Address) -> anyhow::Result<Self> {
        let url = address.url();
        let keyless = std::env::var_os("AWS_ACCESS_KEY_ID").is_none_or(|v| v.is_empty());
        let other_source = [
            "AWS_WEB_IDENTITY_TOKEN_FILE",
            "AWS_CONTAINER_CREDENTIALS_RELATIVE_URI",
            "AWS_CONTAINER_CREDENTIALS_FULL_URI",
            INSTANCE_CREDENTIALS_ENV,
        ]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|v| !v.is_empty()));
        if keyless && !other_source {
            // Without keys the client would ask the machine's metadata service, which off a cloud
            // machine only answers after timeouts: say what to set instead.
            return Err(user_error(format!(
                "cache {url}: no credentials for the bucket `{}`; set AWS_ACCESS_KEY_ID and \
                 AWS_SECRET_ACCESS_KEY (and AWS_ENDPOINT_URL for a store other than AWS S3), or \
                 {INSTANCE_CREDENTIALS_ENV}=1 on a machine whose role grants it",
                address.bucket
            )));
        }
        let retry_s = match std::env::var(RETRY_ENV) {
            Ok(v) => v.trim().parse::<u64>().map_err(|_| {
                user_error(format!("{RETRY_ENV}={v:?} is not a number of seconds (e.g. {RETRY_ENV}=60)"))
            })?,
            Err(_) => 60,
        };
        let retry = RetryConfig {
            max_retries: 10,
            retry_timeout: Duration::from_secs(retry_s),
            ..RetryConfig::default()
        };
        // Timeouts set as keys, not as new client options: those would replace what the
        // environment set (AWS_ALLOW_HTTP among them).
        let (timeout, connect) = (
            AmazonS3ConfigKey::Client(ClientConfigKey::Timeout),
            AmazonS3ConfigKey::Client(ClientConfigKey::ConnectTimeout),
        );
        let store = AmazonS3Builder::from_env()
            .with_bucket_name(&address.bucket)
            .with_retry(retry)
            .with_config(timeout, "30s")
            .with_config(connect, "5s")
            .build()
            .map_err(|e| user_error(format!("cache {url}: cannot configure the client: {e}")))?;
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .thread_name("qsweep-s3")
            .enable_all()
            .build()?;
        let bucket = Self {
            store,
            prefix: address.prefix.clone(),
            url,
            bucket: address.bucket.clone(),
            runtime,
            gone: std::sync::Mutex::new(None),
        };
        bucket.check()?;
        Ok(bucket)
    }

    /// One listing of the cache's prefix: the bucket exists and these credentials may read it.
    fn check(&self) -> anyhow::Result<()> {
        let prefix = self.path("");
        let answer = self.runtime.block_on(self.store.list_with_delimiter(prefix.as_ref()));
        match answer {
            Ok(_) => Ok(()),
            Err(e) => Err(self.refusal(&e).unwrap_or_else(|| self.failed("list", "", e))),
        }
    }

    /// The usage error (exit 2) for an error that says the bucket is missing or refuses us.
    fn refusal(&self, e: &object_store::Error) -> Option<anyhow::Error> {
        let text = format!("{e}");
        let missing = text.contains("NoSuchBucket") || matches!(e, object_store::Error::NotFound { .. });
        let denied = matches!(
            e,
            object_store::Error::PermissionDenied { .. } | object_store::Error::Unauthenticated { .. }
        ) || ["AccessDenied", "InvalidAccessKeyId", "SignatureDoesNotMatch", "403 Forbidden"]
            .iter()
            .any(|w| text.contains(w));
        let b = &self.bucket;
        if missing {
            Some(user_error(format!(
                "cache {}: the bucket `{b}` does not exist (at {}); create it, or fix the name in --cache / \
                 QSWEEP_CACHE ({e})",
                self.url,
                endpoint()
            )))
        } else if denied {
            Some(user_error(format!(
                "cache {}: the bucket `{b}` refused these credentials; check AWS_ACCESS_KEY_ID, \
                 AWS_SECRET_ACCESS_KEY and AWS_REGION ({e})",
                self.url
            )))
        } else {
            None
        }
    }

    /// An error of a request, naming the bucket and the object; one the server did not answer
    /// (after the retries) marks the bucket gone for the requests after it.
    fn failed(&self, what: &str, name: &str, e: object_store::Error) -> anyhow::Error {
        if matches!(e, object_store::Error::Generic { .. }) {
            let mut gone = self.gone.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            gone.get_or_insert_with(|| format!("{e}"));
        }
        anyhow::anyhow!(
            "cache {}: cannot {what} `{name}` in the bucket `{}` at {}: {e} ",
            self.url,
            self.bucket,
            endpoint()
        )
    }

    /// Fail at once if an earlier request found the bucket gone.
    fn alive(&self) -> anyhow::Result<()> {
        match &*self.gone.lock().unwrap_or_else(std::sync::PoisonError::into_inner) {
            Some(why) => Err(anyhow::anyhow!(
                "cache {}: the bucket `{}` at {} stopped answering ({why})",
                self.url,
                self.bucket,
                endpoint()
            )),
            None => Ok(()),
        }
    }

    fn path(&self, name: &str) -> Option<ObjectPath> {
        let full = join(&self.prefix, name);
        (!full.is_empty()).then(|| ObjectPath::from(full))
    }

    fn object(&self, name: &str) -> ObjectPath {
        ObjectPath::from(join(&self.prefix, name))
    }

    /// `name` with the cache's prefix taken off again.
    fn relative(&self, location: &ObjectPath) -> String {
        let full = location.as_ref();
        if self.prefix.is_empty() {
            full.to_string()
        } else {
            full.strip_prefix(&self.prefix).map(|r| r.trim_start_matches('/')).unwrap_or(full).to_string()
        }
    }

    fn listed(&self, meta: &object_store::ObjectMeta) -> Listed {
        Listed { name: self.relative(&meta.location), size: meta.size, modified: meta.last_modified.into() }
    }
}

/// The endpoint requests go to, for messages.
fn endpoint() -> String {
    std::env::var("AWS_ENDPOINT_URL").unwrap_or_else(|_| "AWS S3".to_string())
}

impl Remote for Bucket {
    fn url(&self) -> &str {
        &self.url
    }

    fn list(&self, dir: &str) -> anyhow::Result<Vec<Listed>> {
        self.alive()?;
        let prefix = self.path(dir);
        // The folder alone (its sub-folders are not walked), every page of it.
        let got = self
            .runtime
            .block_on(self.store.list_with_delimiter(prefix.as_ref()))
            .map_err(|e| self.refusal(&e).unwrap_or_else(|| self.failed("list", dir, e)))?;
        let mut out: Vec<Listed> = got.objects.iter().map(|m| self.listed(m)).collect();
        out.sort_by(|a, b| a.name.cmp(&b.name));
        Ok(out)
    }

    fn get(&self, name: &str) -> anyhow::Result<Option<Vec<u8>>> {
        self.alive()?;
        let path = self.object(name);
        let got = self.runtime.block_on(async {
            let r = self.store.get(&path).await?;
            r.bytes().await
        });
        match got {
            Ok(b) => Ok(Some(b.to_vec())),
            Err(object_store::Error::NotFound { .. }) => Ok(None),
            Err(e) => Err(self.failed("read", name, e)),
        }
    }

    fn head(&self, name: &str) -> anyhow::Result<Option<Listed>> {
        self.alive()?;
        match self.runtime.block_on(self.store.head(&self.object(name))) {
            Ok(m) => Ok(Some(self.listed(&m))),
            Err(object_store::Error::NotFound { .. }) => Ok(None),
            Err(e) => Err(self.failed("look at", name, e)),
        }
    }

    fn create(&self, name: &str, body: &[u8]) -> anyhow::Result<bool> {
        self.alive()?;
        let opts = PutOptions { mode: PutMode::Create, ..PutOptions::default() };
        let payload = PutPayload::from(body.to_vec());
        match self.runtime.block_on(self.store.put_opts(&self.object(name), payload, opts)) {
            Ok(_) => Ok(true),
            Err(object_store::Error::AlreadyExists { .. } | object_store::Error::Precondition { .. }) => {
                Ok(false)
            }
            Err(e) => Err(self.failed("write", name, e)),
        }
    }

    fn put(&self, name: &str, body: &[u8]) -> anyhow::Result<()> {
        self.alive()?;
        let payload = PutPayload::from(body.to_vec());
        self.runtime
            .block_on(self.store.put(&self.object(name), payload))
            .map(|_| ())
            .map_err(|e| self.failed("write", name, e))
    }

    fn create_each(&self, objects: &[(String, Vec<u8>)]) -> Vec<anyhow::Result<bool>> {
        if let Err(e) = self.alive() {
            let why = format!("{e:#}");
            return objects.iter().map(|_| Err(anyhow::anyhow!("{why}"))).collect();
        }
        let answers = self.runtime.block_on(futures::future::join_all(objects.iter().map(|(name, body)| {
            let opts = PutOptions { mode: PutMode::Create, ..PutOptions::default() };
            let (path, payload) = (self.object(name), PutPayload::from(body.clone()));
            async move { self.store.put_opts(&path, payload, opts).await }
        })));
        answers
            .into_iter()
            .zip(objects)
            .map(|(answer, (name, _))| match answer {
                Ok(_) => Ok(true),
                Err(object_store::Error::AlreadyExists { .. } | object_store::Error::Precondition { .. }) => {
                    Ok(false)
                }
                Err(e) => Err(self.failed("write", name, e)),
            })
            .collect()
    }

    fn delete_each(&self, names: &[String]) -> anyhow::Result<()> {
        use futures::StreamExt;
        self.alive()?;
        let paths: Vec<object_store::Result<ObjectPath>> = names.iter().map(|n| Ok(self.object(n))).collect();
        let gone = self.store.delete_stream(futures::stream::iter(paths).boxed());
        let answers: Vec<object_store::Result<ObjectPath>> = self.runtime.block_on(gone.collect());
        for answer in answers {
            match answer {
                Ok(_) | Err(object_store::Error::NotFound { .. }) => {}
                Err(e) => return Err(self.failed("remove", &names.join(", "), e)),
            }
        }
        Ok(())
    }

    fn delete(&self, name: &str) -> anyhow::Result<()> {
        self.alive()?;
        match self.runtime.block_on(self.store.delete(&self.object(name))) {
            Ok(()) | Err(object_store::Error::NotFound { .. }) => Ok(()),
            Err(e) => Err(self.failed("remove", name, e)),
        }
    }
}
