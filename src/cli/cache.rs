//! `skytie cache stats|verify|gc --max-size SIZE`: the store maintenance commands (bodies in
//! `crate::cache_cmd`); with `--cache-remote URL`, `verify` and `gc` work on the remote too.

use crate::cli::common::CacheOpt;
use clap::{Args, Subcommand};

#[derive(Args, Debug)]
pub struct CacheArgs {
    #[command(subcommand)]
    pub action: CacheAction,
    #[command(flatten)]
    pub cache: CacheOpt,
}

#[derive(Subcommand, Debug)]
pub enum CacheAction {
    /// Entries and bytes, per stage.
    Stats,
    /// Re-hash every entry; remove and list bad ones (exit 1 if any). With a remote, also download and
    /// check every remote entry and generated folder.
    Verify,
    /// Remove least-recently-used entries until the cache fits (never entries of a running run). With a
    /// remote, also remove the remote results no node record points to any more.
    Gc {
        /// Size limit of the local cache folder, e.g. 10G, 500M, 0.
        #[arg(long, value_name = "SIZE")]
        max_size: String,
        /// With a remote: keep unreachable remote objects younger than this (runs on other hosts upload an
        /// entry just before its node record), e.g. 30m, 6h, 2d, 0.
        #[arg(long, value_name = "AGE", default_value = crate::cache_cmd::DEFAULT_REMOTE_MIN_AGE)]
        remote_min_age: String,
    },
}

pub fn main(args: &CacheArgs) -> i32 {
    let store = match args.cache.open() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    match &args.action {
        CacheAction::Stats => {
            print!("{}", crate::cache_cmd::stats(&store));
            0
        }
        CacheAction::Verify => {
            let (text, ok) = crate::cache_cmd::verify(&store);
            print!("{text}");
            if ok {
                0
            } else {
                1
            }
        }
        CacheAction::Gc {
            max_size,
            remote_min_age,
        } => match crate::cache_cmd::gc_with(&store, max_size, remote_min_age) {
            Ok(text) => {
                print!("{text}");
                0
            }
            Err(e) => {
                eprintln!("error: {e}");
                2
            }
        },
    }
}
