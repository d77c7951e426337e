//! The remote cache's URL: `s3://BUCKET/PREFIX` (S3 and S3-compatible stores such as MinIO), `file:///PATH` (a
//! folder, through object_store's local file system backend) and `memory://NAME` (an in-process store for
//! tests). Parsing only; [`super::Remote::open`] opens it.

use std::path::PathBuf;

/// What every URL error message ends with: the accepted forms.
const FORMS: &str =
    "use s3://BUCKET/PREFIX (S3 or MinIO; credentials and endpoint from the AWS_* environment \
                     variables), file:///ABSOLUTE/PATH or memory://NAME (tests only)";

/// A parsed remote cache location.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RemoteUrl {
    /// A bucket of an S3-compatible store and a key prefix inside it (may be empty).
    S3 { bucket: String, prefix: String },
    /// A folder used as an object store (created if missing).
    File { root: PathBuf },
    /// A named in-process store: every handle of this process with the same name sees the same objects.
    Memory { name: String },
}

/// Why a remote URL was rejected; the message says what to write instead.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("cache remote `{url}`: {problem}")]
pub struct UrlError {
    pub url: String,
    pub problem: String,
}

fn err(url: &str, problem: impl Into<String>) -> UrlError {
    UrlError {
        url: url.to_string(),
        problem: problem.into(),
    }
}

/// `a/b//c/` → `a/b/c`: the key prefix without empty segments.
fn clean_prefix(path: &str) -> String {
    path.split('/')
        .filter(|s| !s.is_empty())
        .collect::<Vec<_>>()
        .join("/")
}

/// Parses a remote cache URL (see the module documentation).
pub fn parse(url: &str) -> Result<RemoteUrl, UrlError> {
    let trimmed = url.trim();
    if trimmed.is_empty() {
        return Err(err(url, format!("empty URL: {FORMS}")));
    }
    let Some((scheme, rest)) = trimmed.split_once("://") else {
        return Err(err(
            url,
            format!("not a URL (no `scheme://`): {FORMS}; a plain folder is the local cache, given with --cache DIR"),
        ));
    };
    match scheme.to_ascii_lowercase().as_str() {
        "s3" | "s3a" => {
            let (bucket, path) = rest.split_once('/').unwrap_or((rest, ""));
            if bucket.is_empty() {
                return Err(err(
                    url,
                    "no bucket: write s3://BUCKET/PREFIX, e.g. s3://survey-cache/skytie (create the bucket first, \
                     e.g. `mc mb` on MinIO or `aws s3 mb`)",
                ));
            }
            let valid_bucket = bucket.len() >= 3
                && bucket.len() <= 63
                && bucket.bytes().all(|b| {
                    b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-' || b == b'.'
                });
            if !valid_bucket {
                return Err(err(
                    url,
                    format!(
                        "`{bucket}` is not a valid bucket name (3–63 characters from a–z, 0–9, '-', '.'); write \
                         s3://BUCKET/PREFIX"
                    ),
                ));
            }
            Ok(RemoteUrl::S3 {
                bucket: bucket.to_string(),
                prefix: clean_prefix(path),
            })
        }
        "file" => {
            // file:///srv/cache → rest = "/srv/cache"; file://localhost/srv/cache is accepted too.
            let path = rest.strip_prefix("localhost").unwrap_or(rest);
            if !path.starts_with('/') {
                return Err(err(
                    url,
                    "file:// needs an absolute path after the two slashes of the scheme, e.g. file:///srv/skytie-remote \
                     (three slashes)",
                ));
            }
            Ok(RemoteUrl::File {
                root: PathBuf::from(path),
            })
        }
        "memory" => {
            let name = clean_prefix(rest);
            Ok(RemoteUrl::Memory { name })
        }
        other => Err(err(url, format!("unknown scheme `{other}://`: {FORMS}"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn s3_urls_give_bucket_and_clean_prefix() {
        assert_eq!(
            parse("s3://survey-cache/skytie/city//").unwrap(),
            RemoteUrl::S3 {
                bucket: "survey-cache".into(),
                prefix: "skytie/city".into()
            }
        );
        assert_eq!(
            parse(" S3://bucket ").unwrap(),
            RemoteUrl::S3 {
                bucket: "bucket".into(),
                prefix: String::new()
            }
        );
    }

    #[test]
    fn file_and_memory_urls() {
        assert_eq!(
            parse("file:///srv/remote").unwrap(),
            RemoteUrl::File {
                root: PathBuf::from("/srv/remote")
            }
        );
        assert_eq!(
            parse("file://localhost/srv/remote").unwrap(),
            RemoteUrl::File {
                root: PathBuf::from("/srv/remote")
            }
        );
        assert_eq!(
            parse("memory://shared").unwrap(),
            RemoteUrl::Memory {
                name: "shared".into()
            }
        );
        assert_eq!(
            parse("memory://").unwrap(),
            RemoteUrl::Memory {
                name: String::new()
            }
        );
    }

    #[test]
    fn errors_say_what_to_write() {
        let e = parse("s3://").unwrap_err().to_string();
        assert!(
            e.contains("no bucket") && e.contains("s3://BUCKET/PREFIX"),
            "{e}"
        );
        let e = parse("s3:///prefix").unwrap_err().to_string();
        assert!(e.contains("no bucket"), "{e}");
        let e = parse("s3://Bad_Bucket/x").unwrap_err().to_string();
        assert!(e.contains("not a valid bucket name"), "{e}");
        let e = parse("gs://bucket/x").unwrap_err().to_string();
        assert!(
            e.contains("unknown scheme `gs://`") && e.contains("s3://BUCKET/PREFIX"),
            "{e}"
        );
        let e = parse("/srv/cache").unwrap_err().to_string();
        assert!(e.contains("not a URL") && e.contains("--cache DIR"), "{e}");
        let e = parse("file://srv/cache").unwrap_err().to_string();
        assert!(e.contains("absolute path") && e.contains("file:///"), "{e}");
        let e = parse("  ").unwrap_err().to_string();
        assert!(e.contains("empty URL"), "{e}");
    }
}
