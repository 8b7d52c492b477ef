//! The flight image for a Cortex-M4F: STM32F405/407 (USART1 on PA9/PA10) or QEMU's `netduinoplus2`
//! (whose first `-serial` is the same USART1). Build it with `cargo fw` from the workspace root.
//!
//! The board layer is kept thin; everything testable lives in the `firmware` library:
//! * USART1 receive interrupt → [`ByteQueue`] (lock-free, single producer and consumer) → main loop →
//!   [`App::push`] → estimate frame → USART1, transmitted by polling TXE. Receiving in the interrupt is
//!   what keeps the link whole on silicon: a step can take milliseconds, during which a 115 200 Bd line
//!   delivers tens of bytes that a polling loop would lose to overruns. A full queue masks the
//!   interrupt until the main loop has taken bytes (QEMU's USART then holds the line back; a board's
//!   UART overruns); each UART overrun is counted and reported as `rx_overruns` in every estimate
//!   frame.
//!   Transmission is a 53-byte burst once per frame and may block.
//! * Clocks: SYSCLK 168 MHz from the HSE crystal through the PLL (`firmware::rcc`, every wait
//!   bounded); where the clock tree does not respond (QEMU does not model RCC) the firmware stays on
//!   the 16 MHz HSI and says so once over defmt. The step budget and USART1's baud divider follow
//!   whichever clock it got. Peripheral clocks are enabled by plain RCC register writes.
//! * Step timing: the DWT cycle counter on silicon; if it does not advance (QEMU), TIM2 with PSC = 0,
//!   which counts one per instruction under `-icount shift=0`.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "This is the Cortex-M4F flight image; on the host it does nothing.\n\
         Build it with `cargo fw` (target/thumbv7em-none-eabihf/firmware/firmware),\n\
         run it in QEMU with `hil-sim run --firmware qemu ...`, or flash it with `probe-rs run`.\n\
         The application logic is the `firmware` library, tested with `cargo test -p firmware`."
    );
}

#[cfg(target_os = "none")]
mod board;
