//! skytie-util: the few utilities that both the engine (root crate) and the photogrammetry crate
//! (`skytie-stages`) need, so that neither has to import the other: atomic file replacement ([`fsutil`]) and
//! huge-page advice for large buffers ([`huge_pages`]).

pub mod fsutil;
pub mod huge_pages;
