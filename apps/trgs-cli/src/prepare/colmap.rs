//! COLMAP's command-line program, stage by stage. Options are named as the installed version
//! names them (COLMAP 3.12 moved `SiftExtraction.use_gpu` to `FeatureExtraction.use_gpu`, for
//! instance): each stage reads its command's help once and passes the name it lists. GPU SIFT is
//! off: most machines this runs on have no CUDA build of COLMAP, and CPU SIFT gives the same
//! features.
use super::Matching;
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The smallest triangulation angles (degrees) of the pair a mapping starts from, tried in turn
/// when the one before found no pair, after COLMAP's default (16): a video panning along a
/// facade moves the camera little between frames, so no pair reaches 16 degrees, while a pair
/// seen at a few degrees still triangulates enough points for the model to grow from it. COLMAP
/// draws its initial pair with RANSAC: the same frames that start at 4 degrees in one run may
/// need 2 in the next (DSC_0050 of the facade captures, docs/captures.md), so one retry is not
/// enough; each costs one mapping, only when the one before failed.
pub const RETRY_INIT_ANGLES: [f64; 3] = [4.0, 2.0, 1.0];

/// The `colmap` program found on this machine, with the threads it may use.
#[derive(Debug)]
pub struct Colmap {
    program: PathBuf,
    version: String,
    threads: i32,
    /// Where each command's output goes (`<command>.log`, appended), if anywhere.
    logs: Option<PathBuf>,
}

impl Colmap {
    /// `program` if it runs (its first line of help is its version), else a named error that
    /// says how to install it.
    pub fn find(program: &Path, threads: i32) -> Result<Self> {
        let output = Command::new(program).arg("help").stdin(Stdio::null()).output();
        let output = match output {
            Ok(o) => o,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!(
                "COLMAP is not installed (no `{}` program on the PATH): install it (Debian and \
                 Ubuntu: `apt install colmap`; macOS: `brew install colmap`; Windows: the \
                 release from colmap.github.io) or pass --colmap PATH",
                program.display()
            ),
            Err(e) => return Err(e).with_context(|| format!("running {}", program.display())),
        };
        let text = String::from_utf8_lossy(&output.stdout).into_owned();
        let version = text.lines().find(|l| l.contains("COLMAP")).unwrap_or("").trim().to_string();
        if version.is_empty() {
            bail!("{} does not answer `help` as COLMAP does: is it COLMAP?", program.display());
        }
        Ok(Self { program: program.to_path_buf(), version, threads, logs: None })
    }

    /// Append each command's output to `<dir>/<command>.log`.
    pub fn logging_to(self, dir: &Path) -> Self {
        Self { logs: Some(dir.to_path_buf()), ..self }
    }

    /// The version line COLMAP prints.
    pub fn version(&self) -> &str {
        &self.version
    }

    /// SIFT features of every image in `images` into `database`, with cameras of `model`: one
    /// for all when `single_camera`, else one per image.
    pub fn extract_features(
        &self,
        database: &Path,
        images: &Path,
        model: &str,
        single_camera: bool,
    ) -> Result<()> {
        let command = "feature_extractor";
        let options = self.options(command)?;
        let mut args = vec![
            ("database_path".to_string(), path(database)),
            ("image_path".to_string(), path(images)),
            ("ImageReader.single_camera".to_string(), u8::from(single_camera).to_string()),
            ("ImageReader.camera_model".to_string(), model.to_string()),
        ];
        args.extend(options.either(&["FeatureExtraction.use_gpu", "SiftExtraction.use_gpu"], "0"));
        let threads = ["FeatureExtraction.num_threads", "SiftExtraction.num_threads"];
        args.extend(options.either(&threads, &self.threads.to_string()));
        self.run(command, &args)
    }

    /// Matches between the images of `database`: every pair, or neighbours in name order.
    pub fn match_features(&self, database: &Path, matching: Matching) -> Result<()> {
        let command = match matching {
            Matching::Exhaustive => "exhaustive_matcher",
            Matching::Sequential => "sequential_matcher",
        };
        let options = self.options(command)?;
        let mut args = vec![("database_path".to_string(), path(database))];
        args.extend(options.either(&["FeatureMatching.use_gpu", "SiftMatching.use_gpu"], "0"));
        let threads = ["FeatureMatching.num_threads", "SiftMatching.num_threads"];
        args.extend(options.either(&threads, &self.threads.to_string()));
        self.run(command, &args)
    }

    /// Incremental mapping into `models` (one folder per model COLMAP makes), starting from a
    /// pair seen at `init_angle` degrees or more (None: COLMAP's default; see
    /// [`RETRY_INIT_ANGLES`]).
    pub fn map(
        &self,
        database: &Path,
        images: &Path,
        models: &Path,
        fix_focal: bool,
        init_angle: Option<f64>,
    ) -> Result<()> {
        std::fs::create_dir_all(models)
            .with_context(|| format!("creating {}", models.display()))?;
        let command = "mapper";
        let options = self.options(command)?;
        let mut args = vec![
            ("database_path".to_string(), path(database)),
            ("image_path".to_string(), path(images)),
            ("output_path".to_string(), path(models)),
        ];
        args.extend(options.either(&["Mapper.num_threads"], &self.threads.to_string()));
        if fix_focal {
            args.push(options.required(command, "Mapper.ba_refine_focal_length", "0")?);
        }
        if let Some(angle) = init_angle {
            args.push(options.required(
                command,
                "Mapper.init_min_tri_angle",
                &angle.to_string(),
            )?);
        }
        self.run(command, &args)
    }

    /// The options `command` lists in its help.
    fn options(&self, command: &str) -> Result<Options> {
        let output = Command::new(&self.program)
            .args([command, "-h"])
            .stdin(Stdio::null())
            .output()
            .with_context(|| format!("running {} {command} -h", self.program.display()))?;
        Ok(Options(String::from_utf8_lossy(&output.stdout).into_owned()))
    }

    /// Run `command` with `args`; its output goes to the log (see [`Colmap::logging_to`]), and a
    /// failure quotes its last lines.
    fn run(&self, command: &str, args: &[(String, String)]) -> Result<()> {
        let mut c = Command::new(&self.program);
        c.arg(command).stdin(Stdio::null());
        for (k, v) in args {
            c.arg(format!("--{k}")).arg(v);
        }
        // COLMAP's Qt part wants a display it does not use for CPU work.
        c.env("QT_QPA_PLATFORM", "offscreen");
        let Some(dir) = &self.logs else {
            let output = c.output().with_context(|| format!("running colmap {command}"))?;
            let text = [output.stdout, output.stderr].concat();
            return check(command, output.status, &String::from_utf8_lossy(&text), None);
        };
        // Straight into the log as it comes: a stage stopped or hung halfway has its output there.
        let log = dir.join(format!("{command}.log"));
        let open = || {
            std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(&log)
                .with_context(|| format!("opening {}", log.display()))
        };
        let mut file = open()?;
        let args: Vec<String> = args.iter().map(|(k, v)| format!("--{k} {v}")).collect();
        let head = format!("\n$ colmap {command} {}\n", args.join(" "));
        std::io::Write::write_all(&mut file, head.as_bytes())
            .with_context(|| format!("writing {}", log.display()))?;
        let start = file.metadata().map(|m| m.len()).unwrap_or(0);
        let status = c
            .stdout(Stdio::from(open()?))
            .stderr(Stdio::from(open()?))
            .status()
            .with_context(|| format!("running colmap {command}"))?;
        let text = std::fs::read(&log).with_context(|| format!("reading {}", log.display()))?;
        let this_run = text.get(start as usize..).unwrap_or_default();
        check(command, status, &String::from_utf8_lossy(this_run), Some(&log))
    }
}

/// A failed command is an error quoting the last lines of its output (all of it in `log`).
fn check(
    command: &str,
    status: std::process::ExitStatus,
    output: &str,
    log: Option<&Path>,
) -> Result<()> {
    if status.success() {
        return Ok(());
    }
    let tail: Vec<&str> = output.lines().rev().take(12).collect();
    let tail: Vec<&str> = tail.into_iter().rev().collect();
    let whole = log.map(|l| format!(", all of its output in {}", l.display())).unwrap_or_default();
    bail!("colmap {command} failed ({status}{whole}):\n{}", tail.join("\n"))
}

/// The help text of one COLMAP command.
struct Options(String);

impl Options {
    /// `(name, value)` for the first of `names` the command lists; nothing if it lists none
    /// (the option does not exist in this version, so its default stands).
    fn either(&self, names: &[&str], value: &str) -> Option<(String, String)> {
        names
            .iter()
            .find(|n| self.0.contains(&format!("--{n} ")))
            .map(|n| (n.to_string(), value.to_string()))
    }

    /// `(name, value)` for an option the user asked for: an error when this version of
    /// `command` does not list it, rather than a run without it.
    fn required(&self, command: &str, name: &str, value: &str) -> Result<(String, String)> {
        match self.either(&[name], value) {
            Some(option) => Ok(option),
            None => bail!(
                "this COLMAP's {command} does not list --{name}, which this run needs (every \
                 COLMAP 3 release does: is --colmap a COLMAP?)"
            ),
        }
    }
}

fn path(p: &Path) -> String {
    p.display().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_program_says_how_to_install_it() {
        let err = Colmap::find(Path::new("no-such-colmap-program"), -1).expect_err("missing");
        let text = err.to_string();
        assert!(text.contains("COLMAP is not installed") && text.contains("apt install"), "{text}");
    }

    #[test]
    fn options_are_named_as_the_version_names_them() {
        let old = Options("  --SiftExtraction.use_gpu arg (=1)\n".into());
        let new = Options("  --FeatureExtraction.use_gpu arg (=1)\n".into());
        let names = ["FeatureExtraction.use_gpu", "SiftExtraction.use_gpu"];
        assert_eq!(old.either(&names, "0"), Some(("SiftExtraction.use_gpu".into(), "0".into())));
        assert_eq!(new.either(&names, "0").map(|o| o.0), Some("FeatureExtraction.use_gpu".into()));
        assert_eq!(Options(String::new()).either(&names, "0"), None);
        let err = Options(String::new()).required("mapper", "Mapper.init_min_tri_angle", "2");
        assert!(err.expect_err("not listed").to_string().contains("--Mapper.init_min_tri_angle"));
    }
}
