//! # propid firmware demo
//!
//! propid-core inside a motor-controller-style loop on a Cortex-M4F (QEMU's mps2-an386):
//!
//! ```text
//!  every 1 ms control tick:
//!    torque setpoint (sinusoid) ─► plant::Load<f32> (the simulator's load model, RK4) ─► measurement
//!    measurement ─► estimate::LoadEstimator<f32> (forgetting factor 0.9995: ~2 s memory)
//!    measurement ─► dsdl::DoF3rdTs ─► node::Node (FrameSplitter, fixed queue) ─► CAN peripheral
//!  every 100 ms: the estimate as zubax.primitive.real32.Vector4 [J, c1, c2, RMS] on subject 111
//! ```
//! At the end it prints the estimated inertia and drag and exits with success only if both are
//! within 5 % of the simulated truth. It also reports the cost of one estimator update and one
//! feedback encode in guest instructions, counted with SysTick under `-icount shift=0` and
//! calibrated against a loop of known length. No allocator is linked: nothing here or in the
//! core can allocate.
#![no_std]
#![no_main]

mod can_glue;

use core::time::Duration;

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use panic_semihosting as _;
use propid_core::can::{FrameSplitter, Mtu, NodeId, Priority, SubjectId, TransferHeader, TransferKind};
use propid_core::dsdl::{BitWriter, DataType, DoF3rdTs};
use propid_core::estimate::{LoadBounds, LoadEstimator};
use propid_core::node::{Node, NodeConfig};
use propid_core::plant::{Load, LoadParams};
use propid_core::time::Instant;

/// The simulated truth.
const INERTIA: f32 = 2.0e-5;
const C2: f32 = 1.5e-8;
/// Control tick [s] and run time [ticks].
const DT: f32 = 1e-3;
const TICKS: u32 = 20_000;
const FEEDBACK_SUBJECT: SubjectId = SubjectId::from_const(110);
const ESTIMATE_SUBJECT: SubjectId = SubjectId::from_const(111);
const NODE_ID: NodeId = NodeId::from_const(42);

type FirmwareNode = Node<2, 2, 64, 32>;

/// SysTick ticks elapsed since `start` (the counter runs down and wraps at 2^24).
fn ticks_since(start: u32) -> u32 {
    start.wrapping_sub(SYST::get_current()) & 0x00FF_FFFF
}

/// Guest instructions per SysTick tick, from a loop of known length (two instructions per turn).
fn instructions_per_tick() -> f32 {
    const TURNS: u32 = 1_000_000;
    let start = SYST::get_current();
    // SAFETY: the loop only decrements a register the asm owns (`inout`), touches no memory and
    // leaves the stack alone; the flags it clobbers are declared by default for `asm!`.
    unsafe {
        core::arch::asm!("1:", "subs {n}, {n}, #1", "bne 1b", n = inout(reg) TURNS => _);
    }
    (2 * TURNS) as f32 / ticks_since(start) as f32
}

/// A tiny deterministic noise source (the firmware has no RNG): ±0.5 of `scale`.
struct Noise(u32);

impl Noise {
    fn next(&mut self, scale: f32) -> f32 {
        self.0 = self.0.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        ((self.0 >> 8) as f32 / (1u32 << 24) as f32 - 0.5) * scale
    }
}

fn feedback(t: f32, load: &Load<f32>, torque: f32, acceleration: f32) -> DoF3rdTs {
    let mut fb = DoF3rdTs::default();
    fb.timestamp.microsecond = (t * 1e6) as u64;
    fb.value.kinematics.base.position = load.position % core::f32::consts::TAU;
    fb.value.kinematics.base.velocity = load.velocity;
    fb.value.kinematics.acceleration = acceleration;
    fb.value.force = torque;
    fb
}

/// zubax.primitive.real32.Vector4.1.0: float32[4], 16 bytes.
fn encode_vector4(values: [f32; 4], out: &mut [u8; 16]) {
    let mut w = BitWriter::new(out);
    for v in values {
        w.write_f32(v);
    }
}

#[entry]
fn main() -> ! {
    let mut cp = cortex_m::Peripherals::take().unwrap();
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(0x00FF_FFFF);
    cp.SYST.clear_current();
    cp.SYST.enable_counter();
    let ipt = instructions_per_tick();

    let node: &'static mut FirmwareNode = cortex_m::singleton!(: FirmwareNode =
        Node::new(NodeConfig::new(NODE_ID, "org.propid.firmware_demo", Mtu::Classic), Instant::ZERO)).unwrap();
    let mut can = can_glue::LoopbackCan { transmitted: 0, bytes: 0 };
    let mut load = Load::new(LoadParams::propeller(INERTIA, C2), 800.0f32);
    let mut estimator = LoadEstimator::<f32>::with_forgetting(0.9995);
    let mut noise = Noise(1);
    let bounds = LoadBounds::<f32>::default();

    for k in 0..TICKS {
        let t = k as f32 * DT;
        let now = Instant::from_micros(u64::from(k) * 1000);
        let torque = 0.05 + 0.04 * libm::sinf(core::f32::consts::TAU * t / 2.0);
        // The drive's measurement, with a little noise.
        let acceleration = load.acceleration(torque) + noise.next(4.0);
        let velocity = load.velocity + noise.next(0.2);
        estimator.update(torque, velocity, acceleration);
        let fb = feedback(t, &load, torque, acceleration);
        let _ = node.publish_message(now, FEEDBACK_SUBJECT, Priority::HIGH, &fb, Duration::from_millis(10));
        if k % 100 == 99 {
            if let Ok(e) = estimator.estimate(&bounds) {
                let mut payload = [0u8; 16];
                encode_vector4([e.mass, e.c1, e.c2, e.rms], &mut payload);
                let _ = node.publish(now, ESTIMATE_SUBJECT, Priority::NOMINAL, &payload, Duration::from_millis(50));
            }
        }
        can_glue::pump(node, &mut can, now, |_| {});
        load.step(DT, torque);
    }

    // Cost of one estimator update and one feedback encode, in guest instructions.
    const N: u32 = 1000;
    let mut bench = LoadEstimator::<f32>::with_forgetting(0.9995);
    let start = SYST::get_current();
    for k in 0..N {
        let w = 800.0 + k as f32;
        bench.update(0.05, w, 1000.0 - w);
    }
    let update_instr = ticks_since(start) as f32 * ipt / N as f32;
    let header = TransferHeader {
        priority: Priority::HIGH,
        kind: TransferKind::Message { subject_id: FEEDBACK_SUBJECT },
        source: Some(NODE_ID),
        transfer_id: 0,
    };
    let fb = feedback(1.0, &load, 0.05, 100.0);
    let mut frames = 0u32;
    let start = SYST::get_current();
    for _ in 0..N {
        let mut buf = [0u8; 23];
        let n = fb.serialize(&mut buf);
        if let Ok(split) = FrameSplitter::new(&header, &buf[..n], Mtu::Classic, Instant::ZERO) {
            for f in split {
                frames += u32::from(f.data().len() as u8 > 0);
            }
        }
    }
    let encode_instr = ticks_since(start) as f32 * ipt / N as f32;

    let result = estimator.estimate(&bounds);
    let ok = match result {
        Ok(e) => {
            let (dj, dc) = ((e.mass / INERTIA - 1.0) * 100.0, (e.c2 / C2 - 1.0) * 100.0);
            hprintln!("firmware-demo: estimated J = {:e} kg*m^2 (truth {:e}, {:+.2} %)", e.mass, INERTIA, dj);
            hprintln!("firmware-demo: estimated c2 = {:e} N*m*s^2/rad^2 (truth {:e}, {:+.2} %), c1 = {:e}", e.c2, C2, dc, e.c1);
            libm::fabsf(dj) < 5.0 && libm::fabsf(dc) < 5.0
        }
        Err(e) => {
            hprintln!("firmware-demo: estimation failed: {:?}", e);
            false
        }
    };
    let stats = node.stats();
    hprintln!(
        "firmware-demo: {} CAN frames ({} bytes) sent, {} heartbeats, {} frames expired in the queue",
        can.transmitted, can.bytes, stats.heartbeats, stats.tx.expired
    );
    hprintln!("firmware-demo: {} instructions per SysTick tick (calibrated)", ipt);
    hprintln!("firmware-demo: cost: estimator update {} instructions, DoF3rdTs encode into {} frames {} instructions", update_instr as u32, frames / N, encode_instr as u32);
    hprintln!("firmware-demo: {}", if ok { "PASS: within 5 % of the simulated truth" } else { "FAIL" });
    debug::exit(if ok { debug::EXIT_SUCCESS } else { debug::EXIT_FAILURE });
    loop {}
}
