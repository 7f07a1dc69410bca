//! Leases and run marks in a bucket, played on a directory serving as one ([`DirRemote`]): the
//! rules of `bucket.rs` without a server (the server's own part is tested in `tests/cli/bucket.rs`).

use super::*;
use crate::cache::leases::{runs, Leases};
use crate::cache::remote::dir::DirRemote;
use crate::cache::TrialRecord;
use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::{run_trial, Algorithm, TrialConfig};

/// The bucket (a directory) and a machine's view of it (its own copy), as a store.
fn bucket() -> (tempfile::TempDir, RemoteRef) {
    let d = tempfile::tempdir().unwrap();
    let remote: RemoteRef = Arc::new(DirRemote::new(&d.path().join("bucket")).unwrap());
    (d, remote)
}

fn machine(d: &tempfile::TempDir, remote: &RemoteRef, name: &str) -> Store {
    Store::open_remote(Arc::clone(remote), &d.path().join(name)).unwrap()
}

fn key(i: u8) -> Key {
    Key([i; 32])
}

fn records(n: u64) -> Vec<TrialRecord> {
    let mut c = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![2, 2], 3);
    c.limits.max_episodes = 3;
    (0..n).map(|seed| TrialRecord::new(c.clone(), seed, run_trial(&c, seed), 0.0)).collect()
}

/// Age the object `name` of the directory-bucket by `by`.
fn age(d: &tempfile::TempDir, name: &str, by: Duration) {
    let f = std::fs::File::options().write(true).open(d.path().join("bucket").join(name)).unwrap();
    f.set_modified(SystemTime::now() - by).unwrap();
}

#[test]
fn a_lease_is_one_runs_until_released_and_names_its_runs_mark() {
    let (d, remote) = bucket();
    let (sa, sb) = (machine(&d, &remote, "a"), machine(&d, &remote, "b"));
    let a = Leases::open(&sa).unwrap();
    let b = Leases::open(&sb).unwrap();
    assert_eq!(a.try_take(key(1)).unwrap(), Take::Taken);
    assert_eq!(b.try_take(key(1)).unwrap(), Take::Busy, "a live run's lease");
    assert_eq!(a.try_take(key(1)).unwrap(), Take::Busy, "held already");
    let body = remote.get(&lease_name(&key(1))).unwrap().unwrap();
    assert_eq!(holder_of(&body).as_deref(), Some(a.run_mark()));
    assert!(b.others_present());
    a.release(&[key(1)]);
    assert_eq!(b.try_take(key(1)).unwrap(), Take::Taken);
    assert_eq!(b.held(), 1);
    assert_eq!(runs::live(&sa).unwrap(), [a.run_mark().to_string(), b.run_mark().to_string()].into());
    drop((a, b));
    assert!(remote.list(LEASES_DIR).unwrap().is_empty(), "every lease released");
    assert!(remote.list(RUNS_DIR).unwrap().is_empty(), "every mark removed");
}

#[test]
fn a_dead_runs_lease_is_taken_over_and_swept_and_a_live_ones_is_not() {
    let (d, remote) = bucket();
    let store = machine(&d, &remote, "a");
    // A run killed by SIGKILL: its mark last written 31 s ago by the store's clock, its leases left.
    remote.put(&mark_name("run-00000000000dead0"), b"node-9 7\n").unwrap();
    age(&d, "_runs/run-00000000000dead0", LEASE + Duration::from_secs(1));
    remote.create(&lease_name(&key(1)), b"run-00000000000dead0 node-9 7\n").unwrap();
    remote.create(&lease_name(&key(2)), b"run-00000000000dead0 node-9 7\n").unwrap();
    // A live run on another machine, and a lease naming no mark (a holder that died making it).
    remote.put(&mark_name("run-00000000000live0"), b"node-8 8\n").unwrap();
    remote.create(&lease_name(&key(3)), b"run-00000000000live0 node-8 8\n").unwrap();
    remote.create(&lease_name(&key(4)), b"garbage").unwrap();
    assert_eq!(live_runs(&remote).unwrap(), ["run-00000000000live0".to_string()].into());
    assert_eq!(sweep(&remote, true).unwrap(), Swept { removed: 3, live: 1 });
    let a = Leases::open(&store).unwrap();
    let took = a.try_take_batch(&[key(1), key(3), key(4)]);
    let took: Vec<Take> = took.into_iter().map(Result::unwrap).collect();
    assert_eq!(took, [Take::Taken, Take::Busy, Take::Taken]);
    assert_eq!(runs::sweep_runs(&remote, false).unwrap(), Swept { removed: 1, live: 2 });
    assert_eq!(sweep(&remote, false).unwrap(), Swept { removed: 1, live: 3 }, "key 2's lease is debris");
    drop(a);
    let left: Vec<String> = remote.list(LEASES_DIR).unwrap().into_iter().map(|o| o.name).collect();
    assert_eq!(left, [lease_name(&key(3))], "only the live run's lease stays");
}

#[test]
fn a_key_stored_since_the_scan_is_stored_not_taken() {
    let (d, remote) = bucket();
    let (sa, sb) = (machine(&d, &remote, "a"), machine(&d, &remote, "b"));
    let b = Leases::open(&sb).unwrap();
    b.reset_view(&sb.keys().unwrap(), false);
    let rows = records(2);
    sa.write_segment(&rows).unwrap();
    assert_eq!(b.try_take(rows[0].key).unwrap(), Take::Stored);
    assert_eq!(b.held(), 0);
    assert!(remote.list(LEASES_DIR).unwrap().is_empty(), "the lease made and removed");
}

#[test]
fn gc_on_a_bucket_leaves_a_live_runs_segments_and_compacts_them_once_it_ended() {
    let (d, remote) = bucket();
    let store = machine(&d, &remote, "a");
    let rows = records(4);
    store.write_segment(&rows[..1]).unwrap();
    store.write_segment(&rows[1..2]).unwrap();
    let run = Leases::open(&store).unwrap();
    let writer = store.clone().writing_as(run.run_mark());
    writer.write_segment(&rows[2..]).unwrap();
    let other = machine(&d, &remote, "b");
    let r = other.gc(None, false).unwrap();
    assert_eq!((r.segments_before, r.segments_after, r.rows_kept, r.rows_live), (3, 2, 2, 2), "{r:?}");
    drop(run);
    let r = other.gc(None, false).unwrap();
    assert_eq!((r.segments_after, r.rows_kept), (1, 4), "{r:?}");
    let names: Vec<String> = remote.list("").unwrap().into_iter().map(|o| o.name).collect();
    assert_eq!(names.len(), 1, "{names:?}");
    assert_eq!(machine(&d, &remote, "c").keys().unwrap().keys.len(), 4);
}
