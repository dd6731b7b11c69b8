//! One function's calls and stack frame from its instructions: what each
//! register, and each word of the function's own frame, holds before each
//! instruction on every path through the function (a forward dataflow over
//! its branches and jump tables; where paths meet, only what they agree on
//! is known).
//!
//! What it follows: constants (`l32r`, `movi`, `addi`, `addmi`, `add`,
//! `sub`, `mov`), the stack pointer plus a known amount, a jump table's
//! slot and entry (`addx4`, `l32i`), and words stored into the frame and
//! loaded back (LLVM spills a callee's address in long functions and calls
//! through `l32i a8, a1, N; callx0 a8`). A call leaves a0 and a2..a11
//! unknown (CALL0 ABI: a12..a15 are callee-saved). Assumed: nothing writes
//! the function's frame but its own stores (LLVM takes no spill slot's
//! address, and a callee given a pointer into the frame writes no slot a
//! call's target was spilled to).
use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::ops::Range;

use super::{parse_hex, writes_first_operand, Call, Function};

/// What a register holds.
#[derive(Clone, Debug, PartialEq)]
enum Reg {
    /// A constant: a literal loaded with l32r, or movi.
    Const(u32),
    /// One of these constants, by the path taken (a callee chosen by a
    /// branch: `with_cache_off` calls SPIRead or SPIWrite through a8).
    OneOf(BTreeSet<u32>),
    /// The address of an entry of a table at that address (addx4).
    TableSlot(u32),
    /// An entry loaded from that table.
    TableEntry(u32),
    /// The stack pointer at the function's entry plus this many bytes.
    Sp(i64),
}

/// What is known before an instruction: the registers a0..a15, and the
/// words of the frame that hold a constant (by offset from the entry's
/// stack pointer).
#[derive(Clone, Debug, PartialEq)]
struct State {
    regs: [Option<Reg>; 16],
    slots: BTreeMap<i64, Reg>,
}

/// The most constants a register is followed as holding, one by path.
const MAX_ONE_OF: usize = 8;

impl State {
    fn unknown() -> Self {
        State { regs: Default::default(), slots: BTreeMap::new() }
    }

    /// Where two paths meet: what both know alike, or the constants either
    /// holds. Whether `self` changed.
    fn meet(&mut self, other: &State) -> bool {
        let before = self.clone();
        for (mine, theirs) in self.regs.iter_mut().zip(other.regs.iter()) {
            *mine = join(mine.as_ref(), theirs.as_ref());
        }
        let slots = std::mem::take(&mut self.slots);
        self.slots = slots
            .into_iter()
            .filter_map(|(slot, value)| Some((slot, join(Some(&value), other.slots.get(&slot))?)))
            .collect();
        *self != before
    }
}

fn join(a: Option<&Reg>, b: Option<&Reg>) -> Option<Reg> {
    let (a, b) = (a?, b?);
    if a == b {
        return Some(a.clone());
    }
    let mut all = constants(a)?;
    all.extend(constants(b)?);
    (all.len() <= MAX_ONE_OF).then_some(Reg::OneOf(all))
}

fn constants(reg: &Reg) -> Option<BTreeSet<u32>> {
    match reg {
        Reg::Const(c) => Some(BTreeSet::from([*c])),
        Reg::OneOf(set) => Some(set.clone()),
        _ => None,
    }
}

const SP: usize = 1;

/// The function's calls and frame. `insns`: (address, mnemonic, operands)
/// in address order; `word` reads the image (literals, jump tables).
pub fn read(
    name: &str,
    body: &Range<u32>,
    insns: &[(u32, &str, &str)],
    word: &impl Fn(u32) -> Option<u32>,
) -> Function {
    let index: BTreeMap<u32, usize> = insns.iter().enumerate().map(|(i, insn)| (insn.0, i)).collect();
    let mut before: Vec<Option<State>> = vec![None; insns.len()];
    let mut entry = State::unknown();
    entry.regs[SP] = Some(Reg::Sp(0));
    let mut todo = VecDeque::new();
    if !insns.is_empty() {
        before[0] = Some(entry);
        todo.push_back(0);
    }
    let mut scratch = Function { name: name.to_string(), calls: Vec::new(), frame: 0, lost_sp: None };
    while let Some(i) = todo.pop_front() {
        let Some(mut state) = before[i].clone() else { continue };
        for next in step(insns[i], &mut state, body, &index, word, &mut scratch) {
            match &mut before[next] {
                Some(known) => {
                    if known.meet(&state) {
                        todo.push_back(next);
                    }
                }
                slot @ None => {
                    *slot = Some(state.clone());
                    todo.push_back(next);
                }
            }
        }
    }
    // The calls and the frame, each instruction once, from what is known
    // before it; code no path reaches (none in LLVM's output) with nothing
    // known.
    let mut function = Function { name: name.to_string(), calls: Vec::new(), frame: 0, lost_sp: None };
    for (i, insn) in insns.iter().enumerate() {
        let mut state = before[i].clone().unwrap_or_else(State::unknown);
        step(*insn, &mut state, body, &index, word, &mut function);
    }
    function
}

fn reg(name: &str) -> Option<usize> {
    name.strip_prefix('a')?.parse().ok().filter(|&n| n < 16)
}

/// An immediate as objdump writes it: decimal (`-64`) or, for `addmi` and
/// large `movi`s, hexadecimal of the 32-bit value (`0xfffff600` = -2560).
pub fn parse_imm(text: &str) -> Option<i64> {
    match text.strip_prefix("0x") {
        Some(hex) => u32::from_str_radix(hex, 16).ok().map(|v| i64::from(v as i32)),
        None => text.parse().ok(),
    }
}

/// One instruction: `state` from before it to after it, its calls and
/// stack pointer into `function`; returns the instructions that may run
/// next.
fn step(
    (addr, mnemonic, operands): (u32, &str, &str),
    state: &mut State,
    body: &Range<u32>,
    index: &BTreeMap<u32, usize>,
    word: &impl Fn(u32) -> Option<u32>,
    function: &mut Function,
) -> Vec<usize> {
    let ops: Vec<&str> = operands.split(',').map(|o| o.split_whitespace().next().unwrap_or("")).collect();
    let op = |i: usize| ops.get(i).copied().unwrap_or("");
    let get = |state: &State, name: &str| reg(name).and_then(|r| state.regs[r].clone());
    let this = index.get(&addr).copied().unwrap_or(usize::MAX);
    let sp_before = state.regs[SP].clone();
    let mut next = vec![this.saturating_add(1)];
    let mut value: Option<Option<Reg>> = None; // what the first operand gets, if written
    match mnemonic {
        "call0" => {
            if let Some(target) = parse_hex(op(0)) {
                function.calls.push(Call::To(target));
            }
        }
        "callx0" => match get(state, op(0)).as_ref().and_then(constants) {
            Some(targets) => function.calls.extend(targets.into_iter().map(Call::To)),
            None => function.calls.push(Call::Unknown(addr)),
        },
        "j" => {
            next = match parse_hex(op(0)) {
                // a jump inside the function is a branch, out of it a tail call
                Some(target) if body.contains(&target) => index.get(&target).copied().into_iter().collect(),
                Some(target) => {
                    function.calls.push(Call::To(target));
                    Vec::new()
                }
                None => Vec::new(),
            }
        }
        "jx" => {
            next = match get(state, op(0)) {
                // a switch: the table's entries inside the function
                Some(Reg::TableEntry(table)) if !table_entries(word, table, body).is_empty() => {
                    table_entries(word, table, body).iter().filter_map(|t| index.get(t).copied()).collect()
                }
                other => {
                    match other.as_ref().and_then(constants) {
                        Some(targets) => function.calls.extend(targets.into_iter().map(Call::To)),
                        None => function.calls.push(Call::Unknown(addr)),
                    }
                    Vec::new()
                }
            }
        }
        "ret" | "ret.n" | "rfe" | "rfi" | "rfde" | "ill" | "ill.n" => next = Vec::new(),
        m if m.starts_with('b') && !m.starts_with("break") => {
            if let Some(target) = ops.last().and_then(|t| parse_hex(t)) {
                next.extend(index.get(&target).copied());
            }
        }
        "l32r" => value = Some(parse_hex(op(1)).and_then(word).map(Reg::Const)),
        "movi" | "movi.n" => value = Some(parse_imm(op(1)).map(|v| Reg::Const(v as u32))),
        "addi" | "addi.n" | "addmi" => {
            value = Some(match (get(state, op(1)), parse_imm(op(2))) {
                (Some(Reg::Sp(k)), Some(imm)) => Some(Reg::Sp(k + imm)),
                (Some(Reg::Const(c)), Some(imm)) => Some(Reg::Const(c.wrapping_add(imm as u32))),
                _ => None,
            })
        }
        "add" | "add.n" | "sub" => {
            let sign = if mnemonic == "sub" { -1 } else { 1 };
            value = Some(match (get(state, op(1)), get(state, op(2))) {
                (Some(Reg::Sp(k)), Some(Reg::Const(c))) => Some(Reg::Sp(k + sign * i64::from(c as i32))),
                (Some(Reg::Const(c)), Some(Reg::Sp(k))) if sign > 0 => Some(Reg::Sp(k + i64::from(c as i32))),
                (Some(Reg::Const(a)), Some(Reg::Const(b))) => {
                    Some(Reg::Const(if sign > 0 { a.wrapping_add(b) } else { a.wrapping_sub(b) }))
                }
                _ => None,
            })
        }
        "mov" | "mov.n" => value = Some(get(state, op(1))),
        "or" if op(1) == op(2) => value = Some(get(state, op(1))),
        "addx4" => {
            value = Some(match get(state, op(2)) {
                Some(Reg::Const(table)) => Some(Reg::TableSlot(table)),
                _ => None,
            })
        }
        "l32i" | "l32i.n" => {
            value = Some(match (get(state, op(1)), parse_imm(op(2))) {
                (Some(Reg::TableSlot(table)), Some(0)) => Some(Reg::TableEntry(table)),
                (Some(Reg::Sp(k)), Some(off)) => state.slots.get(&(k + off)).cloned(),
                _ => None,
            })
        }
        "s32i" | "s32i.n" | "s16i" | "s8i" => {
            if let (Some(Reg::Sp(k)), Some(off)) = (get(state, op(1)), parse_imm(op(2))) {
                // a narrower store spoils the word it falls in
                let slot = (k + off) & !3;
                match get(state, op(0)) {
                    Some(value @ (Reg::Const(_) | Reg::OneOf(_))) if mnemonic.starts_with("s32i") => {
                        _ = state.slots.insert(slot, value)
                    }
                    _ => _ = state.slots.remove(&slot),
                }
            }
        }
        _ => {
            if writes_first_operand(mnemonic) {
                value = Some(None);
            }
        }
    }
    let writes = value.is_some();
    if let (Some(v), Some(r)) = (value, reg(op(0))) {
        state.regs[r] = v;
    }
    if mnemonic.starts_with("call") {
        for r in [0, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11] {
            state.regs[r] = None;
        }
    }
    if reg(op(0)) == Some(SP) && writes {
        match state.regs[SP] {
            Some(Reg::Sp(after)) => {
                function.frame = function.frame.max(u32::try_from(-after).unwrap_or(0));
            }
            // a stack pointer loaded back from memory (our exception
            // handlers' return to the interrupted code): taken as the entry's
            _ if mnemonic.starts_with("l32i") && matches!(sp_before, Some(Reg::Sp(_))) => {
                state.regs[SP] = Some(Reg::Sp(0));
            }
            _ => _ = function.lost_sp.get_or_insert(addr),
        }
    }
    next.retain(|&n| n < index.len());
    next
}

/// The entries of the jump table at `table` that lie inside `body`, read
/// until the first that does not.
pub fn table_entries(word: impl Fn(u32) -> Option<u32>, table: u32, body: &Range<u32>) -> Vec<u32> {
    (0u32..)
        .map_while(|i| word(table.checked_add(i.checked_mul(4)?)?))
        .take_while(|target| body.contains(target))
        .collect()
}
