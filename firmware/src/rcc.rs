//! The STM32F405/407 clock tree: SYSCLK 168 MHz from the HSE crystal through the main PLL, or the
//! 16 MHz HSI when the tree does not respond.
//!
//! The sequence follows RM0090 §6 (RCC) and §3.5 (flash read latency):
//!
//! 1. PWR clock on, regulator at scale 1 (`PWR_CR.VOS`, needed above 144 MHz).
//! 2. HSE on; wait for `HSERDY`.
//! 3. Flash: 5 wait states (2.7–3.6 V at 150–168 MHz), prefetch, instruction and data caches; the
//!    latency is read back before the clock goes up, as the reference manual asks.
//! 4. Bus prescalers: AHB /1, APB1 /4 (≤ 42 MHz), APB2 /2 (≤ 84 MHz).
//! 5. PLL from HSE: VCO input 2 MHz, VCO 336 MHz, P /2 → 168 MHz, Q /7 → 48 MHz; PLL on, wait `PLLRDY`.
//! 6. SYSCLK ← PLL; wait until `SWS` says so.
//!
//! Every wait is bounded ([`POLLS`] reads of the flag). If one times out the steps are undone in
//! reverse (SYSCLK back to HSI, PLL and HSE off, prescalers and flash latency as at reset) and
//! [`configure`] reports [`Fallback`]: the core keeps running on the HSI, which is always on after
//! reset. QEMU's `netduinoplus2` does not model RCC (its registers read 0), so there the HSE wait
//! times out and the firmware runs at 16 MHz; on silicon with a crystal the PLL comes up.
//!
//! The registers are reached through [`Mmio`], so the host tests drive the sequence against a
//! register-level fake and check every write and the fallback.

/// HSI, the internal RC oscillator the core runs on after reset.
pub const HSI_HZ: u32 = 16_000_000;

/// Reads of a ready flag before a wait gives up. One poll is a volatile load, a test and a branch
/// (≈ 6–10 cycles): 200,000 polls are ≈ 75–125 ms at the 16 MHz HSI, well beyond an HSE crystal's
/// start-up of a few ms and the PLL's lock time of ≈ 0.1 ms.
pub const POLLS: u32 = 200_000;

/// Register addresses and bits (RM0090).
pub mod reg {
    pub const RCC: u32 = 0x4002_3800;
    pub const RCC_CR: u32 = RCC;
    pub const RCC_PLLCFGR: u32 = RCC + 0x04;
    pub const RCC_CFGR: u32 = RCC + 0x08;
    pub const RCC_APB1ENR: u32 = RCC + 0x40;
    pub const PWR_CR: u32 = 0x4000_7000;
    pub const FLASH_ACR: u32 = 0x4002_3C00;

    pub const CR_HSEON: u32 = 1 << 16;
    pub const CR_HSERDY: u32 = 1 << 17;
    pub const CR_PLLON: u32 = 1 << 24;
    pub const CR_PLLRDY: u32 = 1 << 25;
    pub const PLLCFGR_SRC_HSE: u32 = 1 << 22;
    pub const CFGR_SW_MASK: u32 = 0b11;
    pub const CFGR_SW_PLL: u32 = 0b10;
    pub const CFGR_SWS_MASK: u32 = 0b11 << 2;
    pub const CFGR_SWS_PLL: u32 = 0b10 << 2;
    /// HPRE (bits 7:4), PPRE1 (12:10), PPRE2 (15:13).
    pub const CFGR_PRESCALERS_MASK: u32 = 0xFCF0;
    /// PPRE1 = 0b101 (/4).
    pub const CFGR_PPRE1_DIV4: u32 = 0b101 << 10;
    /// PPRE2 = 0b100 (/2).
    pub const CFGR_PPRE2_DIV2: u32 = 0b100 << 13;
    pub const APB1ENR_PWREN: u32 = 1 << 28;
    pub const PWR_CR_VOS: u32 = 1 << 14;
    pub const ACR_LATENCY_MASK: u32 = 0b111;
    pub const ACR_PRFTEN: u32 = 1 << 8;
    pub const ACR_ICEN: u32 = 1 << 9;
    pub const ACR_DCEN: u32 = 1 << 10;
}

/// 32-bit memory-mapped register access.
pub trait Mmio {
    fn read(&mut self, addr: u32) -> u32;
    fn write(&mut self, addr: u32, value: u32);
    fn modify(&mut self, addr: u32, f: impl FnOnce(u32) -> u32) {
        let v = self.read(addr);
        self.write(addr, f(v));
    }
}

/// Main-PLL settings (RM0090 §6.3.2): f_VCO = f_HSE / m × n, SYSCLK = f_VCO / p, USB/SDIO = f_VCO / q.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plan {
    pub hse_hz: u32,
    pub m: u32,
    pub n: u32,
    pub p: u32,
    pub q: u32,
    /// Flash wait states at the resulting SYSCLK (2.7–3.6 V supply).
    pub flash_latency: u32,
}

impl Plan {
    /// 168 MHz SYSCLK and 48 MHz for USB from an HSE crystal of a whole number of MHz, 4–26 MHz
    /// (the F407's HSE range; a Discovery board has 8 MHz). `None` if the crystal cannot give
    /// exactly that with a 2 MHz VCO input.
    pub const fn sysclk_168mhz(hse_hz: u32) -> Option<Plan> {
        const VCO_IN_HZ: u32 = 2_000_000;
        if hse_hz < 4_000_000 || hse_hz > 26_000_000 || !hse_hz.is_multiple_of(VCO_IN_HZ) {
            return None;
        }
        let plan = Plan {
            hse_hz,
            m: hse_hz / VCO_IN_HZ,
            n: 168,
            p: 2,
            q: 7,
            flash_latency: 5,
        };
        if plan.is_valid() { Some(plan) } else { None }
    }

    /// The reference manual's ranges: 2 ≤ m ≤ 63, 50 ≤ n ≤ 432, p ∈ {2, 4, 6, 8}, 2 ≤ q ≤ 15,
    /// VCO input 1–2 MHz, VCO output 100–432 MHz, SYSCLK ≤ 168 MHz.
    pub const fn is_valid(&self) -> bool {
        if self.m < 2 || self.m > 63 || self.n < 50 || self.n > 432 || self.q < 2 || self.q > 15 {
            return false;
        }
        if !matches!(self.p, 2 | 4 | 6 | 8) || self.flash_latency > 7 {
            return false;
        }
        let Some(vco_in) = self.hse_hz.checked_div(self.m) else {
            return false;
        };
        if vco_in < 1_000_000 || vco_in > 2_000_000 {
            return false;
        }
        let vco = vco_in.saturating_mul(self.n);
        if vco < 100_000_000 || vco > 432_000_000 {
            return false;
        }
        matches!(vco.checked_div(self.p), Some(f) if f <= 168_000_000)
    }

    /// SYSCLK this plan gives; 0 for a plan with a zero divider (never valid).
    pub const fn sysclk_hz(&self) -> u32 {
        let Some(vco_in) = self.hse_hz.checked_div(self.m) else {
            return 0;
        };
        match vco_in.saturating_mul(self.n).checked_div(self.p) {
            Some(f) => f,
            None => 0,
        }
    }

    /// The PLLCFGR value: M (5:0), N (14:6), P (17:16, (p/2) − 1), source HSE (22), Q (27:24).
    pub const fn pllcfgr(&self) -> u32 {
        self.m
            | self.n << 6
            | (self.p / 2).saturating_sub(1) << 16
            | reg::PLLCFGR_SRC_HSE
            | self.q << 24
    }
}

/// The 8 MHz crystal of an STM32F4-Discovery, the F407 board this firmware names.
pub const DISCOVERY: Plan = Plan {
    hse_hz: 8_000_000,
    m: 4,
    n: 168,
    p: 2,
    q: 7,
    flash_latency: 5,
};
const _: () = assert!(DISCOVERY.is_valid() && DISCOVERY.sysclk_hz() == 168_000_000);

/// Clocks the core and the peripheral buses run at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub struct Clocks {
    pub sysclk_hz: u32,
    /// APB1 (USART2/3, TIM2…).
    pub pclk1_hz: u32,
    /// APB2 (USART1…).
    pub pclk2_hz: u32,
}

impl Clocks {
    /// Reset state: everything on the HSI.
    pub const HSI: Clocks = Clocks {
        sysclk_hz: HSI_HZ,
        pclk1_hz: HSI_HZ,
        pclk2_hz: HSI_HZ,
    };
}

/// Which wait timed out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum Fallback {
    /// The HSE never became ready (no crystal, or a tree that is not emulated).
    HseNotReady,
    /// The flash did not accept the wait states.
    FlashLatency,
    /// The PLL did not lock.
    PllNotLocked,
    /// SYSCLK did not switch to the PLL.
    SwitchNotConfirmed,
}

/// The outcome of [`configure`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum Outcome {
    /// SYSCLK from the PLL.
    Pll(Clocks),
    /// Still on the HSI, with the reason; every change made on the way was undone.
    Hsi(Fallback),
}

impl Outcome {
    pub fn clocks(&self) -> Clocks {
        match self {
            Outcome::Pll(c) => *c,
            Outcome::Hsi(_) => Clocks::HSI,
        }
    }
}

/// Reads `addr` until `addr & mask == want`, at most [`POLLS`] times.
fn wait<M: Mmio>(mmio: &mut M, addr: u32, mask: u32, want: u32) -> bool {
    (0..POLLS).any(|_| mmio.read(addr) & mask == want)
}

/// Runs the sequence of the module docs. Call once, first thing after reset, before any peripheral
/// that depends on a bus clock is configured.
pub fn configure<M: Mmio>(mmio: &mut M, plan: &Plan) -> Outcome {
    use reg::*;
    // 1. Regulator scale 1.
    mmio.modify(RCC_APB1ENR, |v| v | APB1ENR_PWREN);
    mmio.modify(PWR_CR, |v| v | PWR_CR_VOS);
    // 2. HSE.
    mmio.modify(RCC_CR, |v| v | CR_HSEON);
    if !wait(mmio, RCC_CR, CR_HSERDY, CR_HSERDY) {
        mmio.modify(RCC_CR, |v| v & !CR_HSEON);
        return Outcome::Hsi(Fallback::HseNotReady);
    }
    // 3. Flash wait states before the clock rises.
    let acr_before = mmio.read(FLASH_ACR);
    mmio.write(
        FLASH_ACR,
        (acr_before & !ACR_LATENCY_MASK) | plan.flash_latency | ACR_PRFTEN | ACR_ICEN | ACR_DCEN,
    );
    if mmio.read(FLASH_ACR) & ACR_LATENCY_MASK != plan.flash_latency {
        mmio.write(FLASH_ACR, acr_before);
        mmio.modify(RCC_CR, |v| v & !CR_HSEON);
        return Outcome::Hsi(Fallback::FlashLatency);
    }
    // 4. Bus prescalers.
    let cfgr_before = mmio.read(RCC_CFGR);
    mmio.write(
        RCC_CFGR,
        (cfgr_before & !CFGR_PRESCALERS_MASK) | CFGR_PPRE1_DIV4 | CFGR_PPRE2_DIV2,
    );
    // 5. PLL.
    mmio.write(RCC_PLLCFGR, plan.pllcfgr());
    mmio.modify(RCC_CR, |v| v | CR_PLLON);
    let undo = |mmio: &mut M, why| {
        mmio.modify(RCC_CFGR, |v| v & !CFGR_SW_MASK);
        // Back on the HSI before the PLL and HSE go off (a no-op when the switch never happened).
        let _ = wait(mmio, RCC_CFGR, CFGR_SWS_MASK, 0);
        mmio.modify(RCC_CR, |v| v & !(CR_PLLON | CR_HSEON));
        mmio.write(RCC_CFGR, cfgr_before & !CFGR_SW_MASK);
        mmio.write(FLASH_ACR, acr_before);
        Outcome::Hsi(why)
    };
    if !wait(mmio, RCC_CR, CR_PLLRDY, CR_PLLRDY) {
        return undo(mmio, Fallback::PllNotLocked);
    }
    // 6. Switch.
    mmio.modify(RCC_CFGR, |v| (v & !CFGR_SW_MASK) | CFGR_SW_PLL);
    if !wait(mmio, RCC_CFGR, CFGR_SWS_MASK, CFGR_SWS_PLL) {
        return undo(mmio, Fallback::SwitchNotConfirmed);
    }
    let sysclk_hz = plan.sysclk_hz();
    Outcome::Pll(Clocks {
        sysclk_hz,
        pclk1_hz: sysclk_hz / 4,
        pclk2_hz: sysclk_hz / 2,
    })
}

#[cfg(test)]
mod tests {
    use super::reg::*;
    use super::*;
    use std::collections::HashMap;

    /// A register file that behaves like the RCC and flash interface where asked to: ready flags
    /// follow their enable bits after `delay` reads, SWS follows SW, ACR keeps the latency written.
    /// Each part can be made dead (never ready), and every write is recorded in order.
    #[derive(Default)]
    struct Fake {
        regs: HashMap<u32, u32>,
        writes: Vec<(u32, u32)>,
        reads: u32,
        hse_dead: bool,
        pll_dead: bool,
        switch_dead: bool,
        flash_dead: bool,
        /// QEMU's unimplemented device: reads 0, writes ignored.
        unmodelled: bool,
        /// Reads of a flag register before a requested state shows.
        delay: u32,
        pending: u32,
    }

    impl Fake {
        /// Reset values of RM0090: HSI on and ready, PLLCFGR 0x2400_3010, VOS = 1.
        fn f407() -> Fake {
            let mut f = Fake::default();
            f.regs.insert(RCC_CR, 0x0000_0083);
            f.regs.insert(RCC_PLLCFGR, 0x2400_3010);
            f.regs.insert(PWR_CR, PWR_CR_VOS);
            f.delay = 3;
            f
        }
        /// QEMU's unimplemented device: reads 0, writes ignored.
        fn unmodelled() -> Fake {
            Fake {
                unmodelled: true,
                ..Fake::default()
            }
        }
        fn get(&self, a: u32) -> u32 {
            self.regs.get(&a).copied().unwrap_or(0)
        }
    }

    impl Mmio for Fake {
        fn read(&mut self, addr: u32) -> u32 {
            self.reads += 1;
            if self.unmodelled {
                return 0;
            }
            let mut v = self.get(addr);
            if addr == RCC_CR {
                if self.pending > 0 {
                    self.pending -= 1;
                } else {
                    if v & CR_HSEON != 0 && !self.hse_dead {
                        v |= CR_HSERDY;
                    }
                    if v & CR_PLLON != 0 && v & CR_HSERDY != 0 && !self.pll_dead {
                        v |= CR_PLLRDY;
                    }
                }
            }
            if addr == RCC_CFGR && !self.switch_dead {
                v = (v & !CFGR_SWS_MASK) | (v & CFGR_SW_MASK) << 2;
            }
            if addr == FLASH_ACR && self.flash_dead {
                v &= !ACR_LATENCY_MASK;
            }
            v
        }
        fn write(&mut self, addr: u32, value: u32) {
            self.writes.push((addr, value));
            if self.unmodelled {
                return;
            }
            // Ready and status bits are read-only: the fake derives them on every read.
            let v = match addr {
                RCC_CR => {
                    self.pending = self.delay;
                    value & !(CR_HSERDY | CR_PLLRDY)
                }
                RCC_CFGR => value & !CFGR_SWS_MASK,
                _ => value,
            };
            self.regs.insert(addr, v);
        }
    }

    fn index_of(f: &Fake, addr: u32, pred: impl Fn(u32) -> bool) -> usize {
        f.writes
            .iter()
            .position(|&(a, v)| a == addr && pred(v))
            .unwrap_or_else(|| panic!("no write to {addr:#x} matching"))
    }

    #[test]
    fn discovery_plan_is_the_reference_manuals_168_mhz() {
        assert_eq!(DISCOVERY.m, 4);
        assert_eq!(DISCOVERY.sysclk_hz(), 168_000_000);
        // M = 4, N = 168, P = 2 (code 0), HSE, Q = 7.
        assert_eq!(DISCOVERY.pllcfgr(), 4 | 168 << 6 | 1 << 22 | 7 << 24);
        assert_eq!(Plan::sysclk_168mhz(25_000_000), None); // 25 MHz cannot give a 2 MHz VCO input
        assert_eq!(Plan::sysclk_168mhz(12_000_000).map(|p| p.m), Some(6));
        assert_eq!(Plan::sysclk_168mhz(2_000_000), None);
        let mut bad = DISCOVERY;
        bad.n = 200; // VCO 400 MHz, SYSCLK 200 MHz
        assert!(!bad.is_valid());
    }

    #[test]
    fn working_tree_reaches_168_mhz_with_flash_and_buses_set_first() {
        let mut f = Fake::f407();
        let out = configure(&mut f, &DISCOVERY);
        assert_eq!(
            out,
            Outcome::Pll(Clocks {
                sysclk_hz: 168_000_000,
                pclk1_hz: 42_000_000,
                pclk2_hz: 84_000_000,
            })
        );
        assert_eq!(f.get(RCC_PLLCFGR), DISCOVERY.pllcfgr());
        assert_eq!(
            f.get(FLASH_ACR),
            5 | ACR_PRFTEN | ACR_ICEN | ACR_DCEN,
            "5 wait states, prefetch and caches"
        );
        let cfgr = f.get(RCC_CFGR);
        assert_eq!(cfgr & CFGR_SW_MASK, CFGR_SW_PLL);
        assert_eq!(
            cfgr & CFGR_PRESCALERS_MASK,
            CFGR_PPRE1_DIV4 | CFGR_PPRE2_DIV2
        );
        assert_ne!(f.get(RCC_APB1ENR) & APB1ENR_PWREN, 0);
        // Order: regulator, HSE, flash latency, prescalers, PLL config, PLL on, switch.
        let vos = index_of(&f, PWR_CR, |v| v & PWR_CR_VOS != 0);
        let hse = index_of(&f, RCC_CR, |v| v & CR_HSEON != 0);
        let acr = index_of(&f, FLASH_ACR, |v| v & ACR_LATENCY_MASK == 5);
        let pre = index_of(&f, RCC_CFGR, |v| v & CFGR_PRESCALERS_MASK != 0);
        let cfg = index_of(&f, RCC_PLLCFGR, |_| true);
        let on = index_of(&f, RCC_CR, |v| v & CR_PLLON != 0);
        let sw = index_of(&f, RCC_CFGR, |v| v & CFGR_SW_MASK == CFGR_SW_PLL);
        assert!(vos < hse && hse < acr && acr < pre && pre < cfg && cfg < on && on < sw);
        // The waits needed a few reads each, not the bound.
        assert!(f.reads < 100, "{} reads", f.reads);
    }

    #[test]
    fn unmodelled_tree_falls_back_to_hsi_after_a_bounded_wait() {
        let mut f = Fake::unmodelled();
        let out = configure(&mut f, &DISCOVERY);
        assert_eq!(out, Outcome::Hsi(Fallback::HseNotReady));
        assert_eq!(out.clocks(), Clocks::HSI);
        // One bounded wait: the register reads of the HSE wait plus the read-modify-writes.
        assert!(f.reads <= POLLS + 4, "{} reads", f.reads);
        // HSEON was asked for, then withdrawn; nothing about the PLL was touched.
        let last_cr = f
            .writes
            .iter()
            .rev()
            .find(|(a, _)| *a == RCC_CR)
            .map(|w| w.1);
        assert_eq!(last_cr.map(|v| v & CR_HSEON), Some(0));
        assert!(
            f.writes
                .iter()
                .all(|(a, _)| *a != RCC_PLLCFGR && *a != FLASH_ACR)
        );
    }

    fn assert_undone(f: &Fake) {
        assert_eq!(f.get(RCC_CR) & (CR_HSEON | CR_PLLON), 0, "HSE and PLL off");
        assert_eq!(f.get(RCC_CFGR), 0, "SYSCLK on HSI, prescalers as at reset");
        assert_eq!(f.get(FLASH_ACR), 0, "flash latency as at reset");
    }

    #[test]
    fn pll_that_never_locks_is_undone() {
        let mut f = Fake::f407();
        f.pll_dead = true;
        assert_eq!(
            configure(&mut f, &DISCOVERY),
            Outcome::Hsi(Fallback::PllNotLocked)
        );
        assert_undone(&f);
    }

    #[test]
    fn switch_that_never_shows_is_undone() {
        let mut f = Fake::f407();
        f.switch_dead = true;
        assert_eq!(
            configure(&mut f, &DISCOVERY),
            Outcome::Hsi(Fallback::SwitchNotConfirmed)
        );
        // SWS never moved, so SW went back to HSI without waiting on anything else.
        assert_undone(&f);
    }

    #[test]
    fn flash_that_refuses_the_wait_states_stops_before_the_pll() {
        let mut f = Fake::f407();
        f.flash_dead = true;
        assert_eq!(
            configure(&mut f, &DISCOVERY),
            Outcome::Hsi(Fallback::FlashLatency)
        );
        assert!(f.writes.iter().all(|(a, _)| *a != RCC_PLLCFGR));
        assert_eq!(f.get(RCC_CR) & CR_HSEON, 0);
    }
}
