//! The board's event log (`-M esp8266,events=FILE`): one `<virtual ns>
//! <event>` line each, for GPIO edges (`gpio5 1`), UART0 input lines fed
//! (`uart0-rx servo 120 60 5`), resets (`reset watchdog`) and the end of a
//! timed run (`stop`). Pulse and blink figures are measured from the edges.

/// What the board logged.
#[derive(Debug, Default)]
pub struct Events {
    pub edges: Vec<Edge>,
    /// (virtual ns, line) of each UART0 input line, when its first byte arrived.
    pub inputs: Vec<(u64, String)>,
    /// Virtual ns of each watchdog reset.
    pub watchdog_resets: Vec<u64>,
    /// Every other event: (virtual ns, text), e.g. `download-mode`,
    /// `cpu-clock 80000000`, `uart0-baud 74928`, `flash-cache-off 0x...`.
    pub others: Vec<(u64, String)>,
}

/// A pin's level change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    pub ns: u64,
    pub pin: u8,
    pub high: bool,
}

/// A complete high pulse on a pin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pulse {
    pub rise_ns: u64,
    pub width_ns: u64,
}

impl Events {
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut events = Events::default();
        for (n, line) in text.lines().enumerate() {
            let bad = || format!("events line {}: cannot read '{line}'", n + 1);
            let (ns, event) = line.split_once(' ').ok_or_else(bad)?;
            let ns: u64 = ns.parse().map_err(|_| bad())?;
            if let Some(rest) = event.strip_prefix("gpio") {
                let (pin, level) = rest.split_once(' ').ok_or_else(bad)?;
                let pin = pin.parse().map_err(|_| bad())?;
                events.edges.push(Edge { ns, pin, high: level == "1" });
            } else if let Some(input) = event.strip_prefix("uart0-rx ") {
                events.inputs.push((ns, input.trim_end_matches('\r').to_string()));
            } else if event == "reset watchdog" {
                events.watchdog_resets.push(ns);
            } else {
                events.others.push((ns, event.to_string()));
            }
        }
        Ok(events)
    }

    /// The complete high pulses of `pin` that start in `[from_ns, to_ns)`.
    pub fn pulses(&self, pin: u8, from_ns: u64, to_ns: u64) -> Vec<Pulse> {
        let mut pulses = Vec::new();
        let mut rise = None;
        for e in self.edges.iter().filter(|e| e.pin == pin) {
            match (e.high, rise) {
                (true, _) => rise = Some(e.ns),
                (false, Some(r)) => {
                    if (from_ns..to_ns).contains(&r) {
                        pulses.push(Pulse { rise_ns: r, width_ns: e.ns - r });
                    }
                    rise = None;
                }
                (false, None) => {}
            }
        }
        pulses
    }

    /// The first other event that starts with `prefix`: (ns, text).
    pub fn first(&self, prefix: &str) -> Option<&(u64, String)> {
        self.others.iter().find(|(_, e)| e.starts_with(prefix))
    }

    /// The times `pin` changed level in `[from_ns, to_ns)`.
    pub fn toggles(&self, pin: u8, from_ns: u64, to_ns: u64) -> Vec<u64> {
        self.edges.iter().filter(|e| e.pin == pin && (from_ns..to_ns).contains(&e.ns)).map(|e| e.ns).collect()
    }
}

/// The median of the gaps between consecutive times (None for fewer than two).
pub fn median_gap_ns(times: &[u64]) -> Option<u64> {
    let mut gaps: Vec<u64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_unstable();
    gaps.get(gaps.len() / 2).copied()
}

/// `--pulses`' figures for one pin: count, median period, last width.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PulseSummary {
    pub count: usize,
    pub period_us: Option<f64>,
    pub width_us: Option<f64>,
}

pub fn summarize(pulses: &[Pulse]) -> PulseSummary {
    let rises: Vec<u64> = pulses.iter().map(|p| p.rise_ns).collect();
    PulseSummary {
        count: pulses.len(),
        period_us: median_gap_ns(&rises).map(|ns| ns as f64 / 1e3),
        width_us: pulses.last().map(|p| p.width_ns as f64 / 1e3),
    }
}

impl std::fmt::Display for PulseSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let us = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.1}"));
        write!(f, "pulses={} period_us={} width_us={}", self.count, us(self.period_us), us(self.width_us))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LOG: &str = "\
100 gpio5 1
1100 gpio5 0
5000 uart0-rx servo 120 60 5
20100 gpio5 1
21600 gpio5 0
40100 gpio5 1
41700 gpio5 0
60100 gpio5 1
70000 reset watchdog
";

    #[test]
    fn pulses_are_complete_high_periods() {
        let e = Events::parse(LOG).unwrap();
        let p = e.pulses(5, 0, u64::MAX);
        assert_eq!(p.len(), 3, "the pulse still high at the end is not counted");
        assert_eq!(p[1], Pulse { rise_ns: 20100, width_ns: 1500 });
        assert_eq!(e.pulses(5, 20000, 40100).len(), 1);
        assert_eq!(e.inputs, vec![(5000, "servo 120 60 5".to_string())]);
        assert_eq!(e.watchdog_resets, vec![70000]);
    }

    #[test]
    fn summary_is_median_period_and_last_width() {
        let e = Events::parse(LOG).unwrap();
        let s = summarize(&e.pulses(5, 0, u64::MAX));
        assert_eq!(s.count, 3);
        assert_eq!(s.period_us, Some(20.0));
        assert_eq!(s.width_us, Some(1.6));
        assert_eq!(s.to_string(), "pulses=3 period_us=20.0 width_us=1.6");
    }

    #[test]
    fn bad_lines_are_refused() {
        assert!(Events::parse("x gpio5 1\n").is_err());
        assert!(Events::parse("12 gpiox 1\n").is_err());
    }
}
