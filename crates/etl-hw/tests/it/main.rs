//! The integration tests of etl-hw, one binary (linking one test binary per file cost
//! more than running them): each module is one former test file.

mod client_virtual;
mod codec_prop;
mod codec_vectors;
mod faults;
mod fuzz_corpus;
mod hold;
mod transcript;
mod virtual_dynamics;
mod virtual_transport;
