//! # propid-drive-host: the drive's machines on a real bus, a real clock and real files
//!
//! `propid-drive-proto` holds the driver, the simulated Telega and the register client as
//! Sans-IO machines. This crate is everything around them that touches the world:
//!
//! ```text
//!  realtime       run_realtime: one thin loop that sleeps until poll_timeout or a frame, feeds
//!                 the machine, sends what it polls (WouldBlock ⇒ handle_blocked), hands its
//!                 events to the caller and, after the stop, flushes the transport and says
//!                 whether the stop commands left
//!  drive          run_drive: the driver in that loop, rows to a TSV, each flushed before the next
//!  sim_drive      run_sim_drive: the simulated Telega in that loop
//!  telega         BlockingClient: the register client, one op per call
//!  stand          the science's patterns and stand behind the protocol's traits (Played, StandPlant)
//!  register_file  `name: value` files: read, PyCyphal's value rules, rewritten
//!  live           the live view's model: what the page shows, fed without ever blocking the loop
//! ```
//! Nothing here parses a command line, prints or exits: that is the `propid` command's part.
#![deny(missing_docs)]

pub mod drive;
pub mod live;
pub mod realtime;
pub mod register_file;
pub mod sim_drive;
pub mod stand;
pub mod telega;
