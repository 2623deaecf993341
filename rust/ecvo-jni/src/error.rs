//! Errors of the native methods and their one mapping to Java exceptions.

use jni::strings::JNIString;
use jni::{Env, jni_str};

/// What a native call failed with; becomes the Java exception of the same name.
#[derive(Debug, Clone, PartialEq)]
pub enum Failure {
    /// `java.lang.IllegalArgumentException`.
    IllegalArgument(String),
    /// `java.lang.IllegalStateException`.
    IllegalState(String),
    /// `java.lang.RuntimeException`.
    Runtime(String),
    /// A Java exception is already pending.
    Pending,
}

impl From<ecvo_pipeline::Error> for Failure {
    fn from(e: ecvo_pipeline::Error) -> Self {
        use ecvo_pipeline::Error as E;
        match &e {
            E::Core(_)
            | E::InvalidOptions { .. }
            | E::TimestampNotIncreasing { .. }
            | E::TimestampNsNotIncreasing { .. } => Failure::IllegalArgument(e.to_string()),
            E::Closed => Failure::IllegalState(e.to_string()),
            E::StagePanicked { .. } | E::Spawn(_) => Failure::Runtime(e.to_string()),
        }
    }
}

impl From<jni::errors::Error> for Failure {
    fn from(e: jni::errors::Error) -> Self {
        match e {
            jni::errors::Error::JavaException => Failure::Pending,
            e => Failure::Runtime(format!("JNI error: {e}")),
        }
    }
}

pub(crate) fn bad(msg: impl Into<String>) -> Failure {
    Failure::IllegalArgument(msg.into())
}

/// Runs a native method's body; a [`Failure`] is thrown as its Java exception and
/// reported to `native_method!`'s policy as a pending exception (so nothing else is
/// thrown). Panics are caught by the `native_method!` wrapper (`RuntimeException`).
pub(crate) fn run<'local, T>(
    env: &mut Env<'local>,
    body: impl FnOnce(&mut Env<'local>) -> Result<T, Failure>,
) -> jni::errors::Result<T> {
    let failure = match body(env) {
        Ok(v) => return Ok(v),
        Err(f) => f,
    };
    if !env.exception_check() {
        let (class, msg) = match failure {
            Failure::IllegalArgument(m) => (jni_str!("java/lang/IllegalArgumentException"), m),
            Failure::IllegalState(m) => (jni_str!("java/lang/IllegalStateException"), m),
            Failure::Runtime(m) => (jni_str!("java/lang/RuntimeException"), m),
            Failure::Pending => (
                jni_str!("java/lang/RuntimeException"),
                "JNI call failed".into(),
            ),
        };
        log::debug!("ecvo-jni: throwing {class:?}: {msg}");
        let _ = env.throw_new(class, JNIString::from(msg));
    }
    Err(jni::errors::Error::JavaException)
}
