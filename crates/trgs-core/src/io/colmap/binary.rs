//! COLMAP's binary layout (little endian, as COLMAP's `WriteCamerasBinary` etc. write it).
use std::path::Path;

use super::models::{model_by_id, model_by_name};
use super::{
    ColmapCamera, ColmapImage, ColmapModel, ColmapPoint, Located, Location, check_camera,
    check_finite, check_image, id_u32,
};
use crate::io::bytes::{ByteReader, capacity_for};
use crate::io::error::read_bytes;
use crate::io::{FormatError, write_atomic};

/// Read `u64 count` then `count` records with `parse`; each error names the record index, and
/// bytes left after the last record (a count that is too small) are an error too.
fn read_records<T>(
    path: &Path,
    kind: &'static str,
    min_record_size: usize,
    mut parse: impl FnMut(&mut ByteReader<'_>) -> Result<T, String>,
) -> Result<Located<T>, FormatError> {
    let bytes = read_bytes(path)?;
    let mut r = ByteReader::new(&bytes);
    let count = r.u64(&format!("the number of {kind}s")).map_err(|m| FormatError::new(path, m))?;
    let mut out = Vec::with_capacity(capacity_for(count, min_record_size, &r));
    for index in 0..count {
        let at = Location::Record { kind, index, count };
        let item = parse(&mut r).map_err(|m| FormatError::new(path, format!("{at}: {m}")))?;
        out.push((item, at));
    }
    if r.remaining() > 0 {
        return Err(FormatError::new(
            path,
            format!(
                "{} bytes follow the last of the {count} {kind}s the header announces (wrong count?)",
                r.remaining()
            ),
        ));
    }
    Ok(out)
}

pub(super) fn read_cameras(path: &Path) -> Result<Located<ColmapCamera>, FormatError> {
    read_records(path, "camera", 24, |r| {
        let id = id_u32(r.i32("camera_id")?, "camera_id")?;
        let model_id = r.i32("model_id")?;
        let (model, count) = model_by_id(model_id).ok_or_else(|| {
            format!("camera {id}: unknown camera model id {model_id} (COLMAP's ids are 0 to 10)")
        })?;
        let width = r.u64("width")?;
        let height = r.u64("height")?;
        let params = (0..count).map(|_| r.f64("params")).collect::<Result<Vec<_>, _>>()?;
        let cam = ColmapCamera { id, model: model.to_string(), width, height, params };
        check_camera(&cam)?;
        Ok(cam)
    })
}

pub(super) fn read_images(path: &Path) -> Result<Located<ColmapImage>, FormatError> {
    read_records(path, "image", 72, |r| {
        let id = id_u32(r.i32("image_id")?, "image_id")?;
        let mut qvec = [0.0; 4];
        for q in &mut qvec {
            *q = r.f64("qvec")?;
        }
        let mut tvec = [0.0; 3];
        for t in &mut tvec {
            *t = r.f64("tvec")?;
        }
        let camera_id = id_u32(r.i32("camera_id")?, "camera_id")?;
        let name = std::str::from_utf8(r.nul_terminated("the image name")?)
            .map_err(|_| format!("image {id}: the name is not valid UTF-8"))?
            .to_string();
        let n = r.u64("num_points2D")?;
        let mut points2d = Vec::with_capacity(capacity_for(n, 24, r));
        for _ in 0..n {
            let xy = [r.f64("points2D x")?, r.f64("points2D y")?];
            points2d.push((xy, r.i64("points2D point3D_id")?));
        }
        let img = ColmapImage { id, qvec, tvec, camera_id, name, points2d };
        check_image(&img)?;
        Ok(img)
    })
}

pub(super) fn read_points(path: &Path) -> Result<Vec<ColmapPoint>, FormatError> {
    let points = read_records(path, "point", 51, |r| {
        let id = r.u64("point3D_id")?;
        let mut xyz = [0.0; 3];
        for x in &mut xyz {
            *x = r.f64("xyz")?;
        }
        check_finite(|| format!("point {id} xyz"), &xyz)?;
        let rgb = [r.u8("rgb")?, r.u8("rgb")?, r.u8("rgb")?];
        let error = r.f64("error")?;
        let n = r.u64("track_length")?;
        let mut track = Vec::with_capacity(capacity_for(n, 8, r));
        for _ in 0..n {
            let image_id = id_u32(r.i32("track image_id")?, "track image_id")?;
            let point2d_idx = id_u32(r.i32("track point2D_idx")?, "track point2D_idx")?;
            track.push((image_id, point2d_idx));
        }
        Ok(ColmapPoint { id, xyz, rgb, error, track })
    })?;
    Ok(points.into_iter().map(|(p, _)| p).collect())
}

/// An id of ours as COLMAP's signed 32-bit field.
fn id_i32(v: u32, what: &str, path: &Path) -> Result<i32, FormatError> {
    i32::try_from(v)
        .map_err(|_| FormatError::new(path, format!("{what} {v} does not fit COLMAP's int32")))
}

fn count_u64(n: usize) -> [u8; 8] {
    (n as u64).to_le_bytes()
}

pub(super) fn write(model: &ColmapModel, dir: &Path) -> Result<(), FormatError> {
    let path = dir.join("cameras.bin");
    let mut out = count_u64(model.cameras.len()).to_vec();
    for cam in &model.cameras {
        let (model_id, count) = model_by_name(&cam.model).ok_or_else(|| {
            FormatError::new(&path, format!("camera {}: unknown model {:?}", cam.id, cam.model))
        })?;
        if cam.params.len() != count {
            let problem = format!(
                "camera {}: {} takes {count} parameters, has {}",
                cam.id,
                cam.model,
                cam.params.len()
            );
            return Err(FormatError::new(&path, problem));
        }
        out.extend(id_i32(cam.id, "camera id", &path)?.to_le_bytes());
        out.extend(model_id.to_le_bytes());
        out.extend(cam.width.to_le_bytes());
        out.extend(cam.height.to_le_bytes());
        cam.params.iter().for_each(|p| out.extend(p.to_le_bytes()));
    }
    write_atomic(&path, &out)?;

    let path = dir.join("images.bin");
    let mut out = count_u64(model.images.len()).to_vec();
    for img in &model.images {
        if img.name.contains('\0') {
            return Err(FormatError::new(
                &path,
                format!("image {}: the name contains a NUL byte", img.id),
            ));
        }
        out.extend(id_i32(img.id, "image id", &path)?.to_le_bytes());
        img.qvec.iter().chain(&img.tvec).for_each(|v| out.extend(v.to_le_bytes()));
        out.extend(id_i32(img.camera_id, "camera id", &path)?.to_le_bytes());
        out.extend(img.name.as_bytes());
        out.push(0);
        out.extend(count_u64(img.points2d.len()));
        for ([x, y], id) in &img.points2d {
            out.extend(x.to_le_bytes());
            out.extend(y.to_le_bytes());
            out.extend(id.to_le_bytes());
        }
    }
    write_atomic(&path, &out)?;

    let path = dir.join("points3D.bin");
    let mut out = count_u64(model.points.len()).to_vec();
    for p in &model.points {
        out.extend(p.id.to_le_bytes());
        p.xyz.iter().for_each(|v| out.extend(v.to_le_bytes()));
        out.extend(p.rgb);
        out.extend(p.error.to_le_bytes());
        out.extend(count_u64(p.track.len()));
        for &(image_id, idx) in &p.track {
            out.extend(id_i32(image_id, "track image id", &path)?.to_le_bytes());
            out.extend(id_i32(idx, "track point2D index", &path)?.to_le_bytes());
        }
    }
    write_atomic(&path, &out)
}
