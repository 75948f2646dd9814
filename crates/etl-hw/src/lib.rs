//! etl-hw: the Optotune Lens Driver 4 serial protocol, temperature sensors and a virtual
//! lens device for tests and demos.
