//! The design job's `beside`: the search runs on its own thread beside the envelope and may
//! wait for the envelope's corner patterns (issue 29's cost target). Whatever the first task
//! does (ends, fails, panics), a second task waiting for its share goes on, and a second task
//! that never asks does not wait.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;
use vibrofem::Error;
use vibrofem::app::design::job::beside;

#[test]
fn the_second_task_gets_the_first_tasks_share_when_it_asks() {
    let (a, b) = beside(
        || {
            std::thread::sleep(Duration::from_millis(50));
            Ok(vec![1.0, -1.0])
        },
        |v: &Vec<f64>| v.len(),
        |get| Ok(get()),
    );
    assert_eq!(a.unwrap(), vec![1.0, -1.0]);
    assert_eq!(b.unwrap(), Some(2));
}

#[test]
fn a_failing_first_task_releases_the_waiting_second_one() {
    let (a, b) = beside(
        || Err::<u32, _>(Error::Verification("envelope failed".into())),
        |x: &u32| *x,
        |get| Ok(get()),
    );
    assert!(a.is_err());
    assert_eq!(b.unwrap(), None);
}

#[test]
fn a_panicking_first_task_releases_the_second_and_the_panic_goes_on() {
    let released = AtomicBool::new(false);
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        beside(
            || -> vibrofem::Result<u32> { panic!("first task") },
            |x: &u32| *x,
            |get| {
                let v = get();
                released.store(v.is_none(), Ordering::SeqCst);
                Ok(v)
            },
        )
    }));
    assert!(r.is_err(), "the first task's panic is carried on");
    assert!(released.load(Ordering::SeqCst), "the second task got None and ended");
}

#[test]
fn a_second_task_that_never_asks_ends_before_the_first() {
    let second_done = AtomicBool::new(false);
    let (a, b) = beside(
        || {
            // The first task outlasts the second, which does not ask for the share.
            let t = std::time::Instant::now();
            while !second_done.load(Ordering::SeqCst) && t.elapsed() < Duration::from_secs(20) {
                std::thread::sleep(Duration::from_millis(5));
            }
            Ok(second_done.load(Ordering::SeqCst))
        },
        |x: &bool| *x,
        |_get| {
            second_done.store(true, Ordering::SeqCst);
            Ok(7)
        },
    );
    assert!(a.unwrap(), "the second task ran while the first was still running");
    assert_eq!(b.unwrap(), 7);
}
