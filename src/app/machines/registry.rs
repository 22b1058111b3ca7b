//! The list of machines. The command line (and any other front end) iterates over it; adding a
//! machine is one folder beside the others and one line here.

use super::{Machine, autobalancer, balancer_data, crank};

/// Every machine, in the order the help lists them.
pub const MACHINES: &[Machine] = &[crank::MACHINE, autobalancer::MACHINE, balancer_data::MACHINE];

/// The machine run by command `command` (`crank-drive`), if any.
pub fn machine(command: &str) -> Option<&'static Machine> {
    MACHINES.iter().find(|m| m.command == command)
}
