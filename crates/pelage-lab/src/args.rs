//! The command line every lab and benchmark program shares: `--quick`, `--out DIR`.

use std::path::PathBuf;

/// What a lab program was asked for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LabArgs {
    /// Small scenes and few configurations (a CI smoke run).
    pub quick: bool,
    /// The output folder.
    pub out: PathBuf,
}

/// What parsing the command line ended in besides arguments.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LabArgsError {
    /// `--help` was asked for: print this text and exit successfully.
    Help(String),
    /// The arguments are wrong: print this and exit with an error.
    Invalid(String),
}

impl LabArgs {
    /// Parses `args` (without the program name) for the program `name`, which
    /// describes itself with `about` and writes to `default_out` unless told otherwise.
    pub fn parse(
        args: impl IntoIterator<Item = String>,
        name: &str,
        about: &str,
        default_out: &str,
    ) -> Result<Self, LabArgsError> {
        let mut parsed = Self {
            quick: false,
            out: PathBuf::from(default_out),
        };
        let mut it = args.into_iter();
        while let Some(flag) = it.next() {
            match flag.as_str() {
                "--quick" => parsed.quick = true,
                "--out" => {
                    parsed.out = PathBuf::from(
                        it.next()
                            .ok_or_else(|| LabArgsError::Invalid("--out needs a folder".into()))?,
                    )
                }
                "-h" | "--help" => {
                    return Err(LabArgsError::Help(format!(
                        "{name}: {about}\n\n  \
                         --quick     small scenes, few configurations (a CI smoke run)\n  \
                         --out DIR   output folder ({default_out})"
                    )));
                }
                other => {
                    return Err(LabArgsError::Invalid(format!(
                        "unknown argument `{other}`; try --help"
                    )));
                }
            }
        }
        Ok(parsed)
    }

    /// [`LabArgs::parse`] of this process's arguments; prints the help and exits 0, or
    /// prints the error and exits 2.
    pub fn from_env(name: &str, about: &str, default_out: &str) -> Self {
        match Self::parse(std::env::args().skip(1), name, about, default_out) {
            Ok(args) => args,
            Err(LabArgsError::Help(text)) => {
                println!("{text}");
                std::process::exit(0);
            }
            Err(LabArgsError::Invalid(text)) => {
                eprintln!("{name}: {text}");
                std::process::exit(2);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<LabArgs, LabArgsError> {
        LabArgs::parse(
            args.iter().map(|s| s.to_string()),
            "lab",
            "a lab",
            "out/lab",
        )
    }

    #[test]
    fn flags() {
        assert_eq!(
            parse(&[]).unwrap(),
            LabArgs {
                quick: false,
                out: "out/lab".into()
            }
        );
        let a = parse(&["--quick", "--out", "x"]).unwrap();
        assert!(a.quick);
        assert_eq!(a.out, PathBuf::from("x"));
        assert!(matches!(parse(&["--out"]), Err(LabArgsError::Invalid(_))));
        assert!(matches!(parse(&["--nope"]), Err(LabArgsError::Invalid(_))));
        assert!(matches!(parse(&["--help"]), Err(LabArgsError::Help(_))));
    }
}
