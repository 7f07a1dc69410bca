//! The content-addressed trial cache: keys, records and the append-only Parquet store.

pub mod gc;
pub mod key;
pub mod leases;
pub mod record;
pub mod remote;
pub mod rows;
pub mod store;
pub mod verify;

pub use key::{Key, ENGINE_VERSION};
pub use record::TrialRecord;
pub use store::Store;
