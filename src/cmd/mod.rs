//! One module per subcommand; each starts with what it reads and writes.

pub mod simulate;
