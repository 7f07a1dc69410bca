//! Who pays for a lockstep loop's time. Trials that share a loop have no CPU or wall time of their
//! own, so the loop's is split: between two events (a trial joins the loop, a trial leaves it)
//! every trial in the loop takes one step per iteration, so each is charged an equal part of the
//! time that passed. What the trials are charged adds up to what the loop used, exactly. (The
//! loop's time so far in proportion to a trial's steps, when it stops, does not: the loop's cost
//! per step drifts, and the crisp cells of `paper.yaml`, one seed each on one thread, summed to
//! 40.1 CPU s in a process that used 36.6 s.)

/// The time a lockstep loop has used, split among the trials in it as it passes.
#[derive(Debug)]
pub(super) struct Ledger {
    /// CPU and wall clock at the last event (`None`: no CPU clock on this platform).
    last: (Option<f64>, f64),
    /// The trials in the loop: id, CPU and wall seconds charged so far.
    open: Vec<(usize, f64, f64)>,
}

impl Ledger {
    /// A loop starting at CPU time `cpu` and wall time `wall` (seconds, any origin).
    pub(super) fn new(cpu: Option<f64>, wall: f64) -> Self {
        Self { last: (cpu, wall), open: Vec::new() }
    }

    /// Trial `id` joins the loop at (`cpu`, `wall`).
    pub(super) fn join(&mut self, id: usize, cpu: Option<f64>, wall: f64) {
        self.settle(cpu, wall);
        self.open.push((id, 0.0, 0.0));
    }

    /// Trial `id` leaves the loop at (`cpu`, `wall`): its CPU seconds (`None` without a CPU clock)
    /// and wall seconds. An id that never joined is charged nothing.
    pub(super) fn leave(&mut self, id: usize, cpu: Option<f64>, wall: f64) -> (Option<f64>, f64) {
        self.settle(cpu, wall);
        let charged = self.open.iter().position(|t| t.0 == id).map(|i| self.open.swap_remove(i));
        let (c, w) = charged.map_or((0.0, 0.0), |t| (t.1, t.2));
        (cpu.map(|_| c), w)
    }

    /// Split the time since the last event equally among the trials in the loop.
    fn settle(&mut self, cpu: Option<f64>, wall: f64) {
        let n = self.open.len() as f64;
        let d_cpu = cpu.zip(self.last.0).map_or(0.0, |(now, then)| now - then);
        let d_wall = wall - self.last.1;
        if n > 0.0 {
            for t in &mut self.open {
                t.1 += d_cpu / n;
                t.2 += d_wall / n;
            }
        }
        self.last = (cpu, wall);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An oracle for the split: each interval between events shared by the trials open in it.
    #[test]
    fn charges_add_up_to_the_loop_and_split_each_interval_equally() {
        // (event time, joins or leaves, id): times double as CPU and wall seconds.
        let events = [
            (0.0, true, 0),
            (0.0, true, 1),
            (1.0, true, 2),
            (3.0, false, 1),
            (3.5, true, 3),
            (7.0, false, 0),
            (7.0, false, 2),
            (9.0, false, 3),
        ];
        let mut ledger = Ledger::new(Some(0.0), 0.0);
        let mut charged = [0.0; 4];
        for &(t, joins, id) in &events {
            if joins {
                ledger.join(id, Some(t), t);
            } else {
                let (cpu, wall) = ledger.leave(id, Some(t), t);
                assert_eq!(cpu, Some(wall));
                charged[id] = wall;
            }
        }
        // [0,1): 0 and 1 halve 1 s; [1,3): 0, 1, 2 share 2 s; [3,3.5): 0, 2; [3.5,7): 0, 2, 3;
        // [7,9): 3 alone.
        let expect = [
            0.5 + 2.0 / 3.0 + 0.25 + 3.5 / 3.0,
            0.5 + 2.0 / 3.0,
            2.0 / 3.0 + 0.25 + 3.5 / 3.0,
            3.5 / 3.0 + 2.0,
        ];
        for (c, e) in charged.iter().zip(expect) {
            assert!((c - e).abs() < 1e-12, "{charged:?} vs {expect:?}");
        }
        assert!((charged.iter().sum::<f64>() - 9.0).abs() < 1e-12, "the loop's 9 s, no more, no less");
    }

    #[test]
    fn without_a_cpu_clock_only_wall_time_is_charged() {
        let mut ledger = Ledger::new(None, 10.0);
        ledger.join(7, None, 10.0);
        assert_eq!(ledger.leave(7, None, 12.5), (None, 2.5));
        assert_eq!(ledger.leave(8, None, 13.0), (None, 0.0), "never joined");
    }
}
