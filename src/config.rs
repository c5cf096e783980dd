//! Every default lives once: on the clap attribute of the library config struct that defines its
//! flag (`TrainConfig`, `DistillConfig`, `RemoveOptions`, `RefineConfig`, ...). Those structs'
//! `Default` (`default_from_flags!`) is what their flags give when none is passed, read back from
//! clap by `defaults`, so the library, the command line and the pipeline recipes cannot disagree.

/// The value of a config struct when no flag is given: clap parses an empty command line.
pub fn defaults<T: clap::Args + clap::FromArgMatches>() -> T {
    let command = T::augment_args(clap::Command::new("defaults").no_binary_name(true));
    let matches = command
        .try_get_matches_from(std::iter::empty::<String>())
        .unwrap_or_else(|e| panic!("a config struct's flags must all have defaults: {e}"));
    T::from_arg_matches(&matches).unwrap_or_else(|e| panic!("a config struct's defaults do not parse: {e}"))
}

/// `impl Default` for config structs whose defaults are their flags' (`defaults`).
#[macro_export]
macro_rules! default_from_flags {
    ($($config:ty),+ $(,)?) => {
        $(impl Default for $config {
            fn default() -> Self {
                $crate::config::defaults()
            }
        })+
    };
}
