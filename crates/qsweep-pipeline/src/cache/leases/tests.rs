//! Leases between runs, played by several [`Leases`] in one process: each holds its own open
//! files, so their locks exclude each other as two processes' do.

use super::lease::{Holder, LEASE};
use super::lock::Lock;
use super::*;
use crate::cache::TrialRecord;
use qsweep_engine::config::TrialConfig;
use qsweep_engine::env::SystemKind;
use qsweep_engine::repr::ReprKind;
use qsweep_engine::{run_trial, Algorithm};
use std::path::PathBuf;
use std::time::Duration;

fn key(i: u8) -> Key {
    Key([i; 32])
}

fn store() -> (tempfile::TempDir, Store) {
    let dir = tempfile::tempdir().unwrap();
    let store = Store::open(&dir.path().join("cache")).unwrap();
    (dir, store)
}

fn lease_file(store: &Store, k: &Key) -> PathBuf {
    store.dir().join(LEASES_DIR).join(k.hex())
}

/// A lease file as a holder that is not running would have left it.
fn fake_lease(store: &Store, k: &Key, holder: &Holder, age: Duration) -> PathBuf {
    let path = lease_file(store, k);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(&path, holder.to_text()).unwrap();
    let f = File::options().write(true).open(&path).unwrap();
    f.set_modified(SystemTime::now() - age).unwrap();
    path
}

#[test]
fn a_live_lease_is_busy_for_others_until_released() {
    let (_d, store) = store();
    let a = Leases::open(&store).unwrap();
    let b = Leases::open(&store).unwrap();
    assert_eq!(a.try_take(key(1)).unwrap(), Take::Taken);
    assert!(lease_file(&store, &key(1)).exists());
    assert_eq!(b.try_take(key(1)).unwrap(), Take::Busy);
    assert_eq!(running_elsewhere(&store, &[key(1), key(2)]), 1);
    a.release(&[key(1)]);
    assert!(!lease_file(&store, &key(1)).exists());
    assert_eq!(running_elsewhere(&store, &[key(1)]), 0);
    assert_eq!(b.try_take(key(1)).unwrap(), Take::Taken);
    assert_eq!(a.try_take(key(1)).unwrap(), Take::Busy);
    // The holder's file names it.
    let text = std::fs::read_to_string(lease_file(&store, &key(1))).unwrap();
    assert_eq!(Holder::parse(&text), Some(Holder::me()));
    // No temporary files are left in the folder.
    let names: Vec<_> = std::fs::read_dir(store.dir().join(LEASES_DIR)).unwrap().flatten().collect();
    assert_eq!(names.len(), 1);
}

#[test]
fn dropping_the_leases_removes_every_file() {
    let (_d, store) = store();
    let a = Leases::open(&store).unwrap();
    for i in 0..5 {
        assert_eq!(a.try_take(key(i)).unwrap(), Take::Taken);
    }
    assert_eq!(a.held(), 5);
    // Another run on the cache keeps the folder while it has a lease.
    let b = Leases::open(&store).unwrap();
    assert_eq!(b.try_take(key(9)).unwrap(), Take::Taken);
    drop(a);
    assert_eq!(std::fs::read_dir(store.dir().join(LEASES_DIR)).unwrap().count(), 1);
    drop(b);
    assert!(!store.dir().join(LEASES_DIR).exists(), "the last run out removes the folder");
    // A run that meets the folder gone makes it again.
    let c = Leases::open(&store).unwrap();
    std::fs::remove_dir(store.dir().join(LEASES_DIR)).unwrap();
    assert_eq!(c.try_take(key(1)).unwrap(), Take::Taken);
}

#[test]
fn release_registered_frees_the_run_leases_at_once() {
    let (_d, store) = store();
    let a = Leases::open(&store).unwrap();
    let b = Leases::open(&store).unwrap();
    register(&a);
    assert_eq!(a.try_take(key(3)).unwrap(), Take::Taken);
    release_registered();
    assert_eq!(a.held(), 0);
    drop(a);
    release_registered(); // the run is gone: nothing to do
    assert_eq!(b.try_take(key(3)).unwrap(), Take::Taken);
}

#[test]
fn a_dead_holder_on_this_machine_is_taken_over_at_once() {
    let (_d, store) = store();
    // Its lease is fresh, but nobody holds its lock: the kernel dropped it with the process.
    let dead = Holder { host: Holder::me().host, pid: u32::MAX - 1 };
    fake_lease(&store, &key(4), &dead, Duration::ZERO);
    assert_eq!(running_elsewhere(&store, &[key(4)]), 0);
    let a = Leases::open(&store).unwrap();
    assert_eq!(a.try_take(key(4)).unwrap(), Take::Taken);
    let text = std::fs::read_to_string(lease_file(&store, &key(4))).unwrap();
    assert_eq!(Holder::parse(&text), Some(Holder::me()));
}

#[test]
fn a_lease_from_another_machine_holds_for_its_lease_then_is_taken_over() {
    let (_d, store) = store();
    let other = Holder { host: "another-node-of-the-cluster".into(), pid: 7 };
    fake_lease(&store, &key(5), &other, Duration::from_secs(5));
    fake_lease(&store, &key(6), &other, LEASE + Duration::from_secs(1));
    let a = Leases::open(&store).unwrap();
    assert_eq!(a.try_take(key(5)).unwrap(), Take::Busy);
    assert_eq!(running_elsewhere(&store, &[key(5), key(6)]), 1);
    assert_eq!(a.try_take(key(6)).unwrap(), Take::Taken);
    // A heartbeat keeps the taken lease fresh.
    let f = File::options().write(true).open(lease_file(&store, &key(6))).unwrap();
    f.set_modified(SystemTime::now() - LEASE * 2).unwrap();
    a.heartbeat();
    let age = std::fs::metadata(lease_file(&store, &key(6))).unwrap().modified().unwrap().elapsed().unwrap();
    assert!(age < Duration::from_secs(5), "{age:?}");
}

#[test]
fn judging_covers_locks_hosts_and_leases() {
    let me = Holder::me();
    let here_dead = Holder { host: me.host.clone(), pid: u32::MAX - 1 };
    let there = Holder { host: "elsewhere".into(), pid: 1 };
    let cases = [
        // A held lock: live, unless the lease ran out (a lost machine's lock the server kept).
        (Lock::Busy, Some(&there), false, Liveness::Live),
        (Lock::Busy, Some(&there), true, Liveness::Dead),
        (Lock::Busy, None, false, Liveness::Live),
        // A lock we could take: a holder on this machine is dead; elsewhere the lease decides.
        (Lock::Taken, Some(&here_dead), false, Liveness::Dead),
        (Lock::Taken, Some(&there), false, Liveness::Live),
        (Lock::Taken, Some(&there), true, Liveness::Dead),
        (Lock::Taken, None, false, Liveness::Live),
        (Lock::Taken, None, true, Liveness::Dead),
        // No locks: this machine's pids answer, the lease for the rest.
        (Lock::Unsupported, Some(&me), false, Liveness::Live),
        (Lock::Unsupported, Some(&here_dead), false, Liveness::Dead),
        (Lock::Unsupported, Some(&there), false, Liveness::Live),
        (Lock::Unsupported, Some(&there), true, Liveness::Dead),
    ];
    for (lock, holder, stale, want) in cases {
        assert_eq!(judge(lock, holder, &me, stale), want, "{lock:?} {holder:?} stale={stale}");
    }
}

fn records() -> Vec<TrialRecord> {
    let mut c = TrialConfig::paper(SystemKind::BallBeam, ReprKind::Crisp, Algorithm::Q0, vec![2, 2], 3);
    c.limits.max_episodes = 3;
    (0..3).map(|seed| TrialRecord::new(c.clone(), seed, run_trial(&c, seed), 0.1)).collect()
}

#[test]
fn a_key_stored_after_the_scan_is_not_taken() {
    let (_d, store) = store();
    let recs = records();
    store.write_segment(&recs[..1]).unwrap();
    let scan = store.keys().unwrap();
    let a = Leases::open(&store).unwrap();
    a.reset_view(&scan, false);
    assert_eq!(a.try_take(recs[0].key).unwrap(), Take::Stored);
    // Another run stores the second trial after this run's scan.
    store.write_segment(&recs[1..2]).unwrap();
    assert_eq!(a.try_take(recs[1].key).unwrap(), Take::Stored);
    assert_eq!(a.try_take(recs[2].key).unwrap(), Take::Taken);
    assert_eq!(a.held(), 1, "a stored key's lease is not kept");
    // --force: what the scan held is computed again, what others store meanwhile is not.
    let b = Leases::open(&store).unwrap();
    b.reset_view(&scan, true);
    assert_eq!(b.try_take(recs[0].key).unwrap(), Take::Taken);
    assert_eq!(b.try_take(recs[1].key).unwrap(), Take::Stored);
}

#[test]
fn sweep_removes_dead_leases_and_old_temp_files_and_keeps_live_ones() {
    let (_d, store) = store();
    assert_eq!(sweep(&store, false).unwrap(), Swept::default(), "no folder, nothing to do");
    let live = Leases::open(&store).unwrap();
    assert_eq!(live.try_take(key(1)).unwrap(), Take::Taken);
    let dead = Holder { host: Holder::me().host, pid: u32::MAX - 1 };
    fake_lease(&store, &key(2), &dead, Duration::ZERO);
    let other = Holder { host: "elsewhere".into(), pid: 1 };
    fake_lease(&store, &key(3), &other, LEASE * 3);
    fake_lease(&store, &key(4), &other, Duration::ZERO);
    let tmp = store.dir().join(LEASES_DIR).join(".tmp-x.1.2");
    std::fs::write(&tmp, "").unwrap();
    File::options().write(true).open(&tmp).unwrap().set_modified(SystemTime::now() - LEASE * 2).unwrap();
    let dry = sweep(&store, true).unwrap();
    assert_eq!(dry, Swept { removed: 3, live: 2 });
    assert_eq!(std::fs::read_dir(store.dir().join(LEASES_DIR)).unwrap().count(), 5);
    assert_eq!(sweep(&store, false).unwrap(), Swept { removed: 3, live: 2 });
    let mut left: Vec<String> = std::fs::read_dir(store.dir().join(LEASES_DIR))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    let mut want = vec![key(1).hex(), key(4).hex()];
    want.sort();
    assert_eq!(left, want);
}

fn keys(range: std::ops::Range<u8>) -> Vec<Key> {
    range.map(key).collect()
}

fn taken(takes: &[std::io::Result<Take>]) -> Vec<bool> {
    takes.iter().map(|t| matches!(t, Ok(Take::Taken))).collect()
}

/// The inode behind a lease file: the keys of one batch share one.
fn inode(path: &Path) -> u64 {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path).unwrap().ino()
}

#[test]
fn a_batch_is_one_locked_file_linked_under_each_key_and_looks_like_a_lone_lease() {
    let (_d, store) = store();
    let a = Leases::open(&store).unwrap();
    let b = Leases::open(&store).unwrap();
    let ks = keys(1..9);
    assert_eq!(taken(&a.try_take_batch(&ks)), vec![true; 8]);
    assert_eq!(a.held(), 8);
    let first = inode(&lease_file(&store, &ks[0]));
    for k in &ks {
        let path = lease_file(&store, k);
        assert_eq!(inode(&path), first, "one file for the batch");
        assert_eq!(Holder::parse(&std::fs::read_to_string(&path).unwrap()), Some(Holder::me()));
        // Judged as a lone lease is: locked by a live holder.
        let (_f, liveness) = inspect(&path, &Holder::me()).unwrap();
        assert_eq!(liveness, Liveness::Live);
    }
    assert_eq!(running_elsewhere(&store, &ks), 8);
    // Only the links are left in the folder, no temporary name.
    assert_eq!(std::fs::read_dir(store.dir().join(LEASES_DIR)).unwrap().count(), 8);
    // One heartbeat renews every key of the batch.
    let f = File::options().write(true).open(lease_file(&store, &ks[3])).unwrap();
    f.set_modified(SystemTime::now() - LEASE * 2).unwrap();
    assert!(is_stale(
        std::fs::metadata(lease_file(&store, &ks[7])).unwrap().modified().unwrap(),
        SystemTime::now(),
        LEASE
    ));
    a.heartbeat();
    let age = std::fs::metadata(lease_file(&store, &ks[7])).unwrap().modified().unwrap().elapsed().unwrap();
    assert!(age < Duration::from_secs(5), "{age:?}");
    // A released key is free at once; the batch's other keys stay held (its file stays locked).
    a.release(&ks[..2]);
    assert_eq!(taken(&b.try_take_batch(&ks)), [vec![true; 2], vec![false; 6]].concat());
    a.release(&ks[2..]);
    assert_eq!(taken(&b.try_take_batch(&ks[2..])), vec![true; 6]);
}

#[test]
fn batches_of_two_runs_never_overlap_whatever_their_order() {
    let (_d, store) = store();
    let all = keys(0..200);
    let mut backwards = all.clone();
    backwards.reverse();
    // Both runs hold what they leased until both are done, as runs hold unstored trials.
    let done = std::sync::Barrier::new(2);
    let runs: Vec<Vec<Key>> = std::thread::scope(|s| {
        let handles: Vec<_> = [all.clone(), backwards]
            .into_iter()
            .map(|order| {
                let (store, done) = (&store, &done);
                s.spawn(move || {
                    let leases = Leases::open(store).unwrap();
                    let mut mine = Vec::new();
                    for batch in order.chunks(16) {
                        let takes = leases.try_take_batch(batch);
                        mine.extend(
                            batch
                                .iter()
                                .zip(&takes)
                                .filter(|(_, t)| matches!(t, Ok(Take::Taken)))
                                .map(|(k, _)| *k),
                        );
                    }
                    assert_eq!(leases.held(), mine.len());
                    done.wait();
                    mine
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let (a, b): (std::collections::HashSet<Key>, std::collections::HashSet<Key>) =
        (runs[0].iter().copied().collect(), runs[1].iter().copied().collect());
    assert!(a.is_disjoint(&b), "a key leased by both runs");
    assert_eq!(a.len() + b.len(), all.len(), "every key leased by one of them");
}

#[test]
fn a_killed_holders_batch_is_taken_over_key_by_key_and_swept() {
    let (_d, store) = store();
    // What a SIGKILLed run leaves of a batch: one unlocked file (the kernel dropped its lock)
    // naming a holder on this machine, linked under each key it had not released.
    let dead = Holder { host: Holder::me().host, pid: u32::MAX - 1 };
    let ks = keys(10..16);
    let first = fake_lease(&store, &ks[0], &dead, Duration::ZERO);
    for k in &ks[1..] {
        std::fs::hard_link(&first, lease_file(&store, k)).unwrap();
    }
    assert_eq!(running_elsewhere(&store, &ks), 0);
    let a = Leases::open(&store).unwrap();
    assert_eq!(taken(&a.try_take_batch(&ks[..3])), vec![true; 3]);
    for k in &ks[..3] {
        assert_eq!(
            Holder::parse(&std::fs::read_to_string(lease_file(&store, k)).unwrap()),
            Some(Holder::me())
        );
    }
    // The rest are debris until someone needs them: gc removes them, the live batch stays.
    assert_eq!(sweep(&store, false).unwrap(), Swept { removed: 3, live: 3 });
    let b = Leases::open(&store).unwrap();
    assert_eq!(taken(&b.try_take_batch(&ks)), [vec![false; 3], vec![true; 3]].concat());
    // A holder that is dropped (a run that ends or is interrupted) frees its whole batch.
    drop(a);
    assert_eq!(taken(&b.try_take_batch(&ks[..3])), vec![true; 3]);
}

#[test]
fn a_batch_looks_once_at_what_is_stored_and_keeps_no_stored_key() {
    let (_d, store) = store();
    let recs = records();
    let scan = store.keys().unwrap();
    let a = Leases::open(&store).unwrap();
    a.reset_view(&scan, false);
    // Another run stores two of the trials after this run's scan.
    store.write_segment(&recs[..2]).unwrap();
    let ks: Vec<Key> = recs.iter().map(|r| r.key).collect();
    let takes: Vec<Take> = a.try_take_batch(&ks).into_iter().map(Result::unwrap).collect();
    assert_eq!(takes, vec![Take::Stored, Take::Stored, Take::Taken]);
    assert_eq!(a.held(), 1);
    assert!(!lease_file(&store, &ks[0]).exists() && lease_file(&store, &ks[2]).exists());
}
