fn main() {
    etl_calib::cli::main();
}
