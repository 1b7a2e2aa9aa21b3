//! What the loaders' integration tests share: base64 for `data:` URIs, and a count of the panics
//! on the test's thread (a loader's guard catches a panic, and the test must still see it).

#![allow(dead_code)] // each test file uses its own part

use std::cell::Cell;
use std::sync::Once;

/// `bytes` in standard base64 with padding.
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = (c.iter().enumerate()).fold(0u32, |n, (i, &b)| n | u32::from(b) << (16 - 8 * i));
        for k in 0..4 {
            out.push(match k <= c.len() {
                true => A[(n >> (18 - 6 * k) & 63) as usize] as char,
                false => '=',
            });
        }
    }
    out
}

thread_local! {
    /// Panics on this thread since the hook was installed, caught or not.
    static PANICS: Cell<usize> = const { Cell::new(0) };
}

/// Installs (once) a panic hook that counts every panic on its thread, then calls the previous
/// hook.
pub fn count_panics() {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            PANICS.with(|p| p.set(p.get() + 1));
            previous(info);
        }));
    });
}

/// Panics on this thread so far ([`count_panics`] first).
pub fn panics() -> usize {
    PANICS.with(Cell::get)
}
