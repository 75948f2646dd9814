// Link the gate as a self-contained shared library: every symbol must resolve (libc for
// memcpy and friends), so a reachable panic (calling the undefined `etl_core_can_panic`)
// or any allocation shim is a link error.
fn main() {
    println!("cargo:rustc-cdylib-link-arg=-Wl,--no-undefined");
    println!("cargo:rustc-cdylib-link-arg=-lc");
}
