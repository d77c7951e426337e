//! `skytie cache stats|verify|gc --max-size SIZE`: the store maintenance commands (bodies in
//! `crate::cache_cmd`).

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
    /// Re-hash every entry; remove and list bad ones (exit 1 if any).
    Verify,
    /// Remove least-recently-used entries until the cache fits (never entries of a running run).
    Gc {
        /// Size limit, e.g. 10G, 500M, 0.
        #[arg(long, value_name = "SIZE")]
        max_size: String,
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
        CacheAction::Gc { max_size } => match crate::cache_cmd::gc(&store, max_size) {
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
