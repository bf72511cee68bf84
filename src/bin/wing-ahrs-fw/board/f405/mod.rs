//! Board: STM32F405 flight controller (e.g. Matek F405-Wing) — slot for branch `f405`.
//! Must provide the same names as `../qemu.rs` (see `../mod.rs`), plus `memory.x` here.
compile_error!("board-f405 is filled on branch `f405`");
