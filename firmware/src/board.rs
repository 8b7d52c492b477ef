//! STM32F4 / netduinoplus2 board layer: registers, interrupt, clocks, the main loop.
#![allow(unsafe_code)]

use core::ptr::{read_volatile, write_volatile};
use core::sync::atomic::{AtomicBool, Ordering};

use cortex_m::interrupt;
use cortex_m_rt::{entry, exception};
use defmt_rtt as _;
use estimator_core::Estimator;
use estimator_core::wire::MAX_FRAME;
use estimator_core::wire::estimate::TickSource;
use firmware::rcc::{self, Mmio, Outcome};
use firmware::transport::MAILBOX_WORDS;
use firmware::usart::Serviced;
use firmware::{App, ByteQueue, Clock, Config, Transport};
use panic_probe as _;

const BAUD: u32 = 115_200;
/// Room for three sensor frames of the largest kind (kind 4, 326 bytes on the wire) while a step
/// runs: at 115 200 Bd about 12 bytes arrive during a 1-ms step.
const RX_CAPACITY: usize = 1024;

mod reg {
    pub const RCC: usize = 0x4002_3800;
    pub const RCC_AHB1ENR: usize = RCC + 0x30;
    pub const RCC_APB1ENR: usize = RCC + 0x40;
    pub const RCC_APB2ENR: usize = RCC + 0x44;
    pub const GPIOA: usize = 0x4002_0000;
    pub const GPIOA_MODER: usize = GPIOA;
    pub const GPIOA_AFRH: usize = GPIOA + 0x24;
    pub const USART1: usize = firmware::usart::USART1 as usize;
    pub const USART1_SR: usize = firmware::usart::USART1_SR as usize;
    pub const USART1_DR: usize = firmware::usart::USART1_DR as usize;
    pub const USART1_BRR: usize = USART1 + 0x08;
    pub const USART1_CR1: usize = USART1 + 0x0C;
    pub const SR_TXE: u32 = 1 << 7;
    pub const CR1_UE: u32 = 1 << 13;
    pub const CR1_RXNEIE: u32 = 1 << 5;
    pub const CR1_TE: u32 = 1 << 3;
    pub const CR1_RE: u32 = 1 << 2;
    pub const TIM2: usize = 0x4000_0000;
    pub const TIM2_CR1: usize = TIM2;
    pub const TIM2_EGR: usize = TIM2 + 0x14;
    pub const TIM2_CNT: usize = TIM2 + 0x24;
    pub const TIM2_PSC: usize = TIM2 + 0x28;
    pub const TIM2_ARR: usize = TIM2 + 0x2C;
    /// USART1 global interrupt, IRQ 37 on every STM32F4.
    pub const USART1_IRQ: i16 = 37;
}

fn rd(addr: usize) -> u32 {
    // SAFETY: `addr` is one of the fixed, aligned peripheral registers in `reg`.
    unsafe { read_volatile(addr as *const u32) }
}

fn wr(addr: usize, v: u32) {
    // SAFETY: as in `rd`; these registers have no memory-safety side effects.
    unsafe { write_volatile(addr as *mut u32, v) }
}

fn modify(addr: usize, f: impl FnOnce(u32) -> u32) {
    wr(addr, f(rd(addr)));
}

/// The clock-tree registers of `firmware::rcc`, all fixed, aligned peripheral addresses.
struct Registers;

impl Mmio for Registers {
    fn read(&mut self, addr: u32) -> u32 {
        rd(addr as usize)
    }
    fn write(&mut self, addr: u32, value: u32) {
        wr(addr as usize, value)
    }
}

/// Received bytes: the USART1 interrupt is its only producer, the main loop its only consumer (the
/// queue is lock-free, see `firmware::queue`).
static RX: ByteQueue<RX_CAPACITY> = ByteQueue::new();
/// Set by the USART1 interrupt when it found `RX` full and masked itself, leaving the byte in the
/// UART; the main loop unmasks it once it has made room.
static RX_PAUSED: AtomicBool = AtomicBool::new(false);

#[derive(Clone, Copy)]
struct Usart1Irq;
// SAFETY: 37 is USART1's position in the STM32F4 vector table.
unsafe impl cortex_m::interrupt::InterruptNumber for Usart1Irq {
    fn number(self) -> u16 {
        reg::USART1_IRQ as u16
    }
}

/// The step clock chosen at start-up.
enum BoardClock {
    Cycles,
    Instructions,
}

impl Clock for BoardClock {
    fn now(&mut self) -> u32 {
        match self {
            BoardClock::Cycles => cortex_m::peripheral::DWT::cycle_count(),
            BoardClock::Instructions => rd(reg::TIM2_CNT),
        }
    }
    fn source(&self) -> TickSource {
        match self {
            BoardClock::Cycles => TickSource::Cycles,
            BoardClock::Instructions => TickSource::Instructions,
        }
    }
}

fn init_clocks_and_pins() {
    modify(reg::RCC_AHB1ENR, |v| v | 1); // GPIOA
    modify(reg::RCC_APB2ENR, |v| v | 1 << 4); // USART1
    modify(reg::RCC_APB1ENR, |v| v | 1); // TIM2
    // PA9 (TX), PA10 (RX): alternate function 7.
    modify(reg::GPIOA_MODER, |v| (v & !(0b1111 << 18)) | 0b1010 << 18);
    modify(reg::GPIOA_AFRH, |v| (v & !(0xFF << 4)) | 0x77 << 4);
}

/// USART1 is on APB2: BRR = PCLK2 / baud, rounded (16× oversampling, mantissa and fraction as one).
fn init_usart(pclk2_hz: u32) {
    wr(reg::USART1_BRR, pclk2_hz.saturating_add(BAUD / 2) / BAUD);
    wr(
        reg::USART1_CR1,
        reg::CR1_UE | reg::CR1_TE | reg::CR1_RE | reg::CR1_RXNEIE,
    );
}

/// DWT cycles if the counter runs, else TIM2 counting instructions (QEMU `-icount shift=0`).
fn init_step_clock(mut core: cortex_m::Peripherals) -> BoardClock {
    core.DCB.enable_trace();
    core.DWT.enable_cycle_counter();
    let before = cortex_m::peripheral::DWT::cycle_count();
    cortex_m::asm::delay(100);
    if cortex_m::peripheral::DWT::cycle_count() != before {
        return BoardClock::Cycles;
    }
    wr(reg::TIM2_PSC, 0);
    wr(reg::TIM2_ARR, u32::MAX);
    wr(reg::TIM2_EGR, 1); // load PSC now
    wr(reg::TIM2_CR1, 1);
    BoardClock::Instructions
}

/// Sleeps for good: nothing left to serve.
fn halt() -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}

/// Reads and clears the host's opt-in word (see `firmware::transport`).
fn take_transport() -> Transport {
    let [low, high] = MAILBOX_WORDS.map(|a| a as usize);
    let t = Transport::from_mailbox(rd(low), rd(high));
    wr(low, 0);
    wr(high, 0);
    t
}

/// Feeds received bytes to the application, handing each estimate frame to `send`.
fn feed(app: &mut App<'_, BoardClock>, bytes: &[u8], send: &mut impl FnMut(&[u8])) {
    let mut out = [0u8; MAX_FRAME];
    for b in bytes {
        if let Some(len) = app.push(*b, &mut out) {
            send(out.get(..len).unwrap_or(&[]));
        }
    }
}

/// The semihosting path: whole reads from QEMU's stdin, whole writes to its stdout. Only entered
/// when the host opted in, so every `BKPT 0xAB` here has a host to answer it.
fn serve_semihost(mut app: App<'_, BoardClock>) -> ! {
    use cortex_m_semihosting::{hio, nr, syscall};
    // SAFETY: OPEN takes a NUL-terminated name, its mode and the name's length without the NUL.
    let rx = unsafe { syscall!(OPEN, c":tt".as_ptr(), nr::open::R, 3) };
    let tx = hio::hstdout();
    let (false, Ok(mut tx)) = (rx == usize::MAX, tx) else {
        defmt::error!("semihosting console did not open; halting");
        halt()
    };
    let mut send = |bytes: &[u8]| {
        // A failed write is a host that has gone away; the next read ends the loop.
        let _ = tx.write_all(bytes);
    };
    send(&[estimator_core::wire::DELIMITER]);
    let mut buf = [0u8; 256];
    loop {
        // SAFETY: READ writes at most `buf.len()` bytes into `buf`; it returns how many it did NOT read.
        let left = unsafe { syscall!(READ, rx, buf.as_mut_ptr(), buf.len()) };
        let n = buf.len().saturating_sub(left);
        if n == 0 {
            defmt::info!("semihosting console closed; halting");
            halt()
        }
        feed(&mut app, buf.get(..n).unwrap_or(&[]), &mut send);
    }
}

fn send(bytes: &[u8]) {
    for b in bytes {
        while rd(reg::USART1_SR) & reg::SR_TXE == 0 {}
        wr(reg::USART1_DR, u32::from(*b));
    }
}

#[entry]
fn main() -> ! {
    let Some(core) = cortex_m::Peripherals::take() else {
        // Only reachable if something else took them first; there is nothing to run without them.
        loop {
            cortex_m::asm::wfi();
        }
    };
    // 168 MHz from the HSE crystal through the PLL, or the 16 MHz HSI where the clock tree does not
    // respond (QEMU does not model RCC): said once, then the firmware runs on whichever it got.
    let outcome = rcc::configure(&mut Registers, &rcc::DISCOVERY);
    let clocks = outcome.clocks();
    match outcome {
        Outcome::Pll(c) => defmt::info!("SYSCLK {} Hz from the PLL", c.sysclk_hz),
        Outcome::Hsi(why) => defmt::warn!(
            "clock tree not responding ({}): running on the 16 MHz HSI",
            why
        ),
    }
    init_clocks_and_pins();
    let clock = init_step_clock(core);
    let transport = take_transport();
    defmt::info!(
        "estimator firmware up; step clock {}, link {}",
        clock.source(),
        transport
    );
    let app = App::new(
        Estimator::shipped(),
        clock,
        Config::fifty_ms_at(clocks.sysclk_hz),
    );
    if transport == Transport::Semihost {
        serve_semihost(app);
    }
    serve_usart(app, clocks.pclk2_hz)
}

/// The USART1 path: bytes from the receive interrupt's queue, replies by polling TXE.
fn serve_usart(mut app: App<'_, BoardClock>, pclk2_hz: u32) -> ! {
    init_usart(pclk2_hz);
    // SAFETY: unmasking can break a critical section that relies on this interrupt being masked;
    // there is none: the handler only pushes to the lock-free `RX` and reads USART1.
    unsafe { cortex_m::peripheral::NVIC::unmask(Usart1Irq) };

    // A lone delimiter says "ready": receivers skip empty frames, and hil-sim waits for it before
    // sending (bytes that reach USART1 before UE/RE are set are dropped).
    send(&[estimator_core::wire::DELIMITER]);
    let mut batch = [0u8; 64];
    loop {
        let n = batch
            .iter_mut()
            .map_while(|slot| RX.pop().map(|b| *slot = b))
            .count();
        if n > 0 && RX_PAUSED.swap(false, Ordering::AcqRel) {
            // SAFETY: as above; the bytes just taken made room for the one waiting in the UART.
            unsafe { cortex_m::peripheral::NVIC::unmask(Usart1Irq) };
        }
        if n == 0 {
            // Sleep with interrupts masked: a byte arriving after the check still wakes the core
            // (its interrupt stays pending through WFI and runs when the mask is lifted).
            interrupt::free(|_| {
                if RX.is_empty() {
                    cortex_m::asm::wfi();
                }
            });
            continue;
        }
        app.set_rx_overruns(RX.overruns());
        feed(&mut app, batch.get(..n).unwrap_or(&[]), &mut send);
    }
}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    if irqn != reg::USART1_IRQ {
        return;
    }
    // The only producer of `RX`. A full queue leaves the byte in the UART: mask this interrupt
    // until the main loop has taken some (it unmasks, and the interrupt, still pending, runs again).
    // QEMU's USART then holds the next byte back, so a host that sends faster than the firmware
    // reads loses nothing; on a board the UART overruns (ORE, counted when the interrupt runs again).
    if firmware::usart::service_rx(&mut Registers, &RX) == Serviced::QueueFull {
        cortex_m::peripheral::NVIC::mask(Usart1Irq);
        RX_PAUSED.store(true, Ordering::Release);
    }
}
