//! A command failure: an error plus the exit code it maps to.

/// Exit code for bad input: usage errors, unreadable or invalid files, invalid parameters.
pub const BAD_INPUT: u8 = 2;
/// Exit code for a job that failed for another reason (e.g. an output could not be written).
pub const JOB_FAILED: u8 = 1;

/// An error on its way to `main`, with the exit code it ends the process with.
#[derive(Debug)]
pub struct Failure {
    pub code: u8,
    pub error: anyhow::Error,
}

/// Tags the error of a `Result` with an exit code.
pub trait ExitCodeExt<T> {
    /// The error is the user's input (exit code 2).
    fn bad_input(self) -> Result<T, Failure>;
    /// The error is a failure of the job itself (exit code 1).
    fn job_failed(self) -> Result<T, Failure>;
}

impl<T, E: Into<anyhow::Error>> ExitCodeExt<T> for Result<T, E> {
    fn bad_input(self) -> Result<T, Failure> {
        self.map_err(|e| Failure {
            code: BAD_INPUT,
            error: e.into(),
        })
    }
    fn job_failed(self) -> Result<T, Failure> {
        self.map_err(|e| Failure {
            code: JOB_FAILED,
            error: e.into(),
        })
    }
}
