//! COLMAP's text layout: `#` comment lines, whitespace-separated fields, and two lines per image
//! in `images.txt` (the pose line, then the keypoint line, which may be empty).
use std::fmt::Write as _;
use std::path::Path;
use std::str::FromStr;

use super::{
    ColmapCamera, ColmapImage, ColmapModel, ColmapPoint, Located, Location, check_camera,
    check_finite, check_image,
};
use crate::io::error::read_text;
use crate::io::{FormatError, write_atomic};

/// The whitespace-separated fields of one line, parsed with messages that name the field.
struct Fields<'a> {
    rest: &'a str,
}

impl<'a> Fields<'a> {
    fn new(line: &'a str) -> Self {
        Self { rest: line.trim() }
    }

    fn token(&mut self, what: &str) -> Result<&'a str, String> {
        if self.rest.is_empty() {
            return Err(format!("{what} is missing"));
        }
        let (tok, rest) = self.rest.split_once(char::is_whitespace).unwrap_or((self.rest, ""));
        self.rest = rest.trim_start();
        Ok(tok)
    }

    fn parse<T: FromStr>(&mut self, what: &str) -> Result<T, String> {
        let tok = self.token(what)?;
        tok.parse()
            .map_err(|_| format!("{what}: cannot read {tok:?} as a {}", std::any::type_name::<T>()))
    }

    /// Everything left on the line (an image name may contain spaces).
    fn remainder(&self) -> &'a str {
        self.rest
    }

    fn is_empty(&self) -> bool {
        self.rest.is_empty()
    }
}

fn is_data(line: &str) -> bool {
    let t = line.trim();
    !t.is_empty() && !t.starts_with('#')
}

/// Parse every data line (1-based line numbers in errors) with `parse`.
fn read_lines<T>(
    path: &Path,
    mut parse: impl FnMut(&mut Fields<'_>) -> Result<T, String>,
) -> Result<Located<T>, FormatError> {
    let text = read_text(path)?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate().filter(|(_, l)| is_data(l)) {
        let at = Location::Line(i + 1);
        let item = parse(&mut Fields::new(line))
            .map_err(|m| FormatError::new(path, format!("{at}: {m}")))?;
        out.push((item, at));
    }
    Ok(out)
}

pub(super) fn read_cameras(path: &Path) -> Result<Located<ColmapCamera>, FormatError> {
    read_lines(path, |f| {
        let id = f.parse("CAMERA_ID")?;
        let model = f.token("MODEL")?.to_string();
        let width = f.parse("WIDTH")?;
        let height = f.parse("HEIGHT")?;
        let mut params = Vec::new();
        while !f.is_empty() {
            params.push(f.parse("PARAMS")?);
        }
        let cam = ColmapCamera { id, model, width, height, params };
        check_camera(&cam)?;
        Ok(cam)
    })
}

pub(super) fn read_images(path: &Path) -> Result<Located<ColmapImage>, FormatError> {
    let text = read_text(path)?;
    let mut lines = text.lines().enumerate();
    let mut out = Vec::new();
    // As COLMAP's reader: comments and blank lines are skipped before a pose line, but the line
    // right after it is always the keypoint line, even when blank (an image without keypoints).
    while let Some((i, line)) = lines.next() {
        if !is_data(line) {
            continue;
        }
        let at = Location::Line(i + 1);
        let fail = |m: String| FormatError::new(path, format!("{at}: {m}"));
        let mut img = parse_image_line(line).map_err(fail)?;
        if let Some((j, keypoints)) = lines.next() {
            img.points2d = parse_keypoints(keypoints).map_err(|m| {
                FormatError::new(
                    path,
                    format!("line {} (keypoints of image {}): {m}", j + 1, img.id),
                )
            })?;
        }
        out.push((img, at));
    }
    Ok(out)
}

fn parse_image_line(line: &str) -> Result<ColmapImage, String> {
    let mut f = Fields::new(line);
    let id = f.parse("IMAGE_ID")?;
    let qvec = [f.parse("QW")?, f.parse("QX")?, f.parse("QY")?, f.parse("QZ")?];
    let tvec = [f.parse("TX")?, f.parse("TY")?, f.parse("TZ")?];
    let camera_id = f.parse("CAMERA_ID")?;
    let name = f.remainder().to_string();
    if name.is_empty() {
        return Err("NAME is missing".into());
    }
    let img = ColmapImage { id, qvec, tvec, camera_id, name, points2d: Vec::new() };
    check_image(&img)?;
    Ok(img)
}

fn parse_keypoints(line: &str) -> Result<Vec<([f64; 2], i64)>, String> {
    let mut f = Fields::new(line);
    let mut out = Vec::new();
    while !f.is_empty() {
        let xy = [f.parse("X")?, f.parse("Y")?];
        out.push((xy, f.parse("POINT3D_ID")?));
    }
    Ok(out)
}

pub(super) fn read_points(path: &Path) -> Result<Vec<ColmapPoint>, FormatError> {
    let points = read_lines(path, |f| {
        let id = f.parse("POINT3D_ID")?;
        let xyz = [f.parse("X")?, f.parse("Y")?, f.parse("Z")?];
        check_finite(|| format!("point {id} xyz"), &xyz)?;
        let rgb = [f.parse("R")?, f.parse("G")?, f.parse("B")?];
        let error = f.parse("ERROR")?;
        let mut track = Vec::new();
        while !f.is_empty() {
            track.push((f.parse("TRACK IMAGE_ID")?, f.parse("TRACK POINT2D_IDX")?));
        }
        Ok(ColmapPoint { id, xyz, rgb, error, track })
    })?;
    Ok(points.into_iter().map(|(p, _)| p).collect())
}

/// Floats print in Rust's shortest round-trip form, so a text model reads back bit-exactly.
fn join<T: std::fmt::Display>(values: impl IntoIterator<Item = T>) -> String {
    values.into_iter().map(|v| v.to_string()).collect::<Vec<_>>().join(" ")
}

pub(super) fn write(model: &ColmapModel, dir: &Path) -> Result<(), FormatError> {
    let mut s = String::new();
    s.push_str("# Camera list with one line of data per camera:\n");
    s.push_str("#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n");
    let _ = writeln!(s, "# Number of cameras: {}", model.cameras.len());
    for c in &model.cameras {
        let _ = writeln!(s, "{} {} {} {} {}", c.id, c.model, c.width, c.height, join(&c.params));
    }
    write_atomic(&dir.join("cameras.txt"), s.as_bytes())?;

    let path = dir.join("images.txt");
    let mut s = String::new();
    s.push_str("# Image list with two lines of data per image:\n");
    s.push_str("#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n");
    s.push_str("#   POINTS2D[] as (X, Y, POINT3D_ID)\n");
    let _ = writeln!(s, "# Number of images: {}", model.images.len());
    for img in &model.images {
        if img.name.contains(['\n', '\r']) || img.name.trim() != img.name || img.name.is_empty() {
            let problem = format!(
                "image {}: the name {:?} cannot be stored in a text model",
                img.id, img.name
            );
            return Err(FormatError::new(&path, problem));
        }
        let pose = join(img.qvec.iter().chain(&img.tvec));
        let _ = writeln!(s, "{} {pose} {} {}", img.id, img.camera_id, img.name);
        let kp =
            img.points2d.iter().map(|([x, y], id)| format!("{x} {y} {id}")).collect::<Vec<_>>();
        let _ = writeln!(s, "{}", kp.join(" "));
    }
    write_atomic(&path, s.as_bytes())?;

    let mut s = String::new();
    s.push_str("# 3D point list with one line of data per point:\n");
    s.push_str("#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n");
    let _ = writeln!(s, "# Number of points: {}", model.points.len());
    for p in &model.points {
        let track = p.track.iter().map(|(i, k)| format!("{i} {k}")).collect::<Vec<_>>();
        let _ =
            writeln!(s, "{} {} {} {} {}", p.id, join(p.xyz), join(p.rgb), p.error, track.join(" "));
    }
    write_atomic(&dir.join("points3D.txt"), s.as_bytes())
}
