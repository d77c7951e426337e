//! skytie-util: the few utilities that both the engine (root crate) and the photogrammetry crate
//! (`skytie-stages`) need, so that neither has to import the other: atomic file replacement ([`fsutil`]),
//! CSV cells and files ([`csv_out`]), huge-page advice for large buffers ([`huge_pages`]) and the report of a parameter outside its range
//! ([`violation`]).

pub mod csv_out;
pub mod fsutil;
pub mod huge_pages;
pub mod violation;
