//! The integration tests of etl-report, one binary (linking one test binary per file cost
//! more than running them): each module is one former test file.

mod outliers;
mod report_files;
