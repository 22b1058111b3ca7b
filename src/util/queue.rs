//! Tasks of unequal size on the current thread pool, each taken by whichever worker is free
//! (the ready task of highest priority), rather than split among the workers ahead of time as
//! rayon's `par_iter` does: at 119k DOFs that gave one worker of two the two heaviest subtrees
//! of the factorisation, and it finished 0.1 s after the other.

use std::sync::Mutex;

/// Tasks forming a forest, on up to `rayon::current_num_threads()` workers: a task waits for
/// all the tasks whose `parent` it is, and a free worker takes the ready task of highest
/// `priority` (ties: the lower index). `f(i)` runs each task once; after a task's error no
/// task is started any more, and of the errors met the one of the lowest task index is
/// returned. What a task computes must not depend on the schedule (only on its children
/// being complete): the schedule follows the workers' speeds, so a core the host takes away
/// for a while delays a share of the remaining tasks rather than one whole list.
pub fn forest<E: Send>(
    parent: &[Option<usize>],
    priority: &[u64],
    f: impl Fn(usize) -> Result<(), E> + Sync,
) -> Result<(), E> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let n = parent.len();
    assert_eq!(priority.len(), n);
    let mut pending = vec![0usize; n];
    for p in parent.iter().flatten() {
        pending[*p] += 1;
    }
    struct State<E> {
        pending: Vec<usize>,
        ready: BinaryHeap<(u64, Reverse<usize>)>,
        taken: usize,
        running: usize,
        error: Option<(usize, E)>,
        /// A task's panic, passed on once every worker has stopped (a waiting worker would
        /// otherwise wait for the panicked task forever).
        panic: Option<Box<dyn std::any::Any + Send>>,
    }
    let ready = (0..n)
        .filter(|&i| pending[i] == 0)
        .map(|i| (priority[i], Reverse(i)))
        .collect();
    let state = Mutex::new(State {
        pending,
        ready,
        taken: 0,
        running: 0,
        error: None,
        panic: None,
    });
    let wake = std::sync::Condvar::new();
    let work = || {
        let Ok(mut st) = state.lock() else { return };
        loop {
            // Done: every task taken, or an error (or panic) and nothing left running; or
            // nothing ready and nothing running (a cycle among the parents: the check below).
            let stopped = st.error.is_some() || st.panic.is_some();
            let stalled = st.ready.is_empty() && st.running == 0;
            if st.taken == n || (stopped && st.running == 0) || stalled {
                wake.notify_all();
                return;
            }
            let next = if stopped { None } else { st.ready.pop() };
            let Some((_, Reverse(i))) = next else {
                st = match wake.wait(st) {
                    Ok(g) => g,
                    Err(_) => return,
                };
                continue;
            };
            st.taken += 1;
            st.running += 1;
            drop(st);
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(i)));
            st = match state.lock() {
                Ok(g) => g,
                Err(_) => return,
            };
            st.running -= 1;
            match r {
                Ok(Ok(())) => {
                    if let Some(p) = parent[i] {
                        st.pending[p] -= 1;
                        if st.pending[p] == 0 {
                            st.ready.push((priority[p], Reverse(p)));
                        }
                    }
                }
                Ok(Err(e)) => {
                    if st.error.as_ref().is_none_or(|(j, _)| i < *j) {
                        st.error = Some((i, e));
                    }
                }
                Err(payload) => {
                    st.panic.get_or_insert(payload);
                }
            }
            wake.notify_all();
        }
    };
    let workers = rayon::current_num_threads().max(1).min(n.max(1));
    if workers <= 1 {
        work();
    } else {
        rayon::scope(|s| {
            for _ in 1..workers {
                s.spawn(|_| work());
            }
            work();
        });
    }
    let st = state.into_inner().unwrap_or_else(|e| e.into_inner());
    if let Some(payload) = st.panic {
        std::panic::resume_unwind(payload);
    }
    match st.error {
        Some((_, e)) => Err(e),
        None => {
            assert_eq!(st.taken, n, "every task of a forest runs (the parents form no cycle)");
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    /// Every task runs once and after all its children; an error stops the rest.
    #[test]
    fn forest_runs_children_first_and_stops_at_an_error() {
        use std::sync::Mutex;
        // 0..8 leaves; 8 waits for 0..4, 9 for 4..8, 10 for 8 and 9; 11 alone.
        let mut parent = vec![Some(8); 4];
        parent.extend([Some(9); 4]);
        parent.extend([Some(10), Some(10), None, None]);
        let priority: Vec<u64> = (0..12).map(|i| (i * 7 % 5) as u64).collect();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        let order = Mutex::new(Vec::new());
        let r: Result<(), ()> = pool.install(|| {
            super::forest(&parent, &priority, |i| {
                order.lock().unwrap().push(i);
                Ok(())
            })
        });
        assert!(r.is_ok());
        let order = order.into_inner().unwrap();
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..12).collect::<Vec<_>>());
        let pos = |t: usize| order.iter().position(|&x| x == t).unwrap();
        for (c, p) in parent.iter().enumerate() {
            if let Some(p) = p {
                assert!(pos(c) < pos(*p), "task {c} ran after its parent {p}: {order:?}");
            }
        }
        // A failing leaf: its parent and grandparent never run; the error comes back.
        let ran = Mutex::new(Vec::new());
        let r = pool.install(|| {
            super::forest(&parent, &priority, |i| {
                ran.lock().unwrap().push(i);
                if i == 5 { Err(i) } else { Ok(()) }
            })
        });
        assert_eq!(r, Err(5));
        let ran = ran.into_inner().unwrap();
        assert!(!ran.contains(&9) && !ran.contains(&10), "{ran:?}");
        // One worker, and no task at all.
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let count = Mutex::new(0);
        let r: Result<(), ()> = one.install(|| {
            super::forest(&parent, &priority, |_| {
                *count.lock().unwrap() += 1;
                Ok(())
            })
        });
        assert!(r.is_ok());
        assert_eq!(count.into_inner().unwrap(), 12);
        assert!(super::forest::<()>(&[], &[], |_| Ok(())).is_ok());
        // A panicking task is passed on to the caller once the others have stopped; nobody
        // waits for it forever.
        let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            pool.install(|| {
                super::forest::<()>(&parent, &priority, |i| {
                    assert_ne!(i, 2, "task 2 fails");
                    Ok(())
                })
            })
        }));
        assert!(caught.is_err());
        // Parents in a cycle: a clear panic, not workers waiting forever.
        let cycle = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            pool.install(|| super::forest::<()>(&[Some(1), Some(0), None], &[0, 0, 0], |_| Ok(())))
        }));
        assert!(cycle.is_err());
    }
}
