//! A frame's planes as researchers have them, turned into what the engine reads:
//! grey `(H, W)` or colour `(H, W, 3|4)` uint8 intensity (or float in [0, 1], as
//! Open3D's `RGBDImage` holds it), uint16 raw or float metres depth (NaN or 0: no
//! measurement), numpy arrays or anything `numpy.asarray` takes (the buffer protocol:
//! `open3d.geometry.Image`, `memoryview`; `__array__`), and masked arrays, whose
//! masked pixels lose their depth. C-contiguous uint8 grey and uint16 depth without
//! a mask are read in place; everything else is converted once into a buffer the
//! tracker reuses from frame to frame.

use ecvo_io::png::rgb_to_gray;
use numpy::ndarray::{ArrayViewD, Axis, Ix2};
use numpy::{
    Element, PyArrayDescrMethods, PyArrayDyn, PyArrayMethods, PyReadonlyArray2, PyUntypedArray,
    PyUntypedArrayMethods, dtype,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

use crate::arrays::{plane, row_major};
use crate::settings::type_name;

/// The order of a colour image's channels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channels {
    /// Red, green, blue (PIL, imageio, Open3D, matplotlib).
    Rgb,
    /// Blue, green, red (OpenCV).
    Bgr,
}

impl Channels {
    /// Parses `"rgb"` / `"bgr"`.
    pub fn parse(name: &str) -> PyResult<Self> {
        match name {
            "rgb" => Ok(Channels::Rgb),
            "bgr" => Ok(Channels::Bgr),
            _ => Err(PyValueError::new_err(format!(
                "channels must be \"rgb\" or \"bgr\", got {name:?}"
            ))),
        }
    }
}

/// A plane for the engine: the caller's array read in place, or the converted copy
/// in the tracker's scratch buffer.
pub enum Plane<'py, T: Element> {
    /// Borrowed (copied into scratch only if not C-contiguous).
    Array(PyReadonlyArray2<'py, T>),
    /// Already in scratch.
    Scratch,
}

impl<T: Element + Copy> Plane<'_, T> {
    /// The values in row-major order.
    pub fn values<'a>(&'a self, scratch: &'a mut Vec<T>) -> &'a [T] {
        match self {
            Plane::Array(a) => row_major(a, scratch),
            Plane::Scratch => scratch,
        }
    }
}

/// `obj` as a numpy array: itself, or `numpy.asarray(obj)` (buffer protocol,
/// `__array__`); anything else is a TypeError naming what was expected.
fn ndarray<'py>(obj: &Bound<'py, PyAny>, name: &str, what: &str) -> PyResult<Bound<'py, PyAny>> {
    if obj.cast::<PyUntypedArray>().is_ok() {
        return Ok(obj.clone());
    }
    let py = obj.py();
    let converted = py
        .import("numpy")?
        .call_method1("asarray", (obj,))
        .ok()
        .filter(|a| {
            a.cast::<PyUntypedArray>()
                .is_ok_and(|u| u.ndim() > 0 && u.dtype().kind() != b'O')
        });
    converted.ok_or_else(|| {
        PyTypeError::new_err(format!(
            "{name} must be a numpy.ndarray of {what} or an object with the buffer \
             protocol (such as open3d.geometry.Image), got {}",
            type_name(obj)
        ))
    })
}

/// The `(H, W)` mask of a masked array (a colour pixel is masked if any channel is),
/// row-major; None for anything else or a mask with nothing masked.
fn mask_of(obj: &Bound<'_, PyAny>, h: usize, w: usize) -> PyResult<Option<Vec<bool>>> {
    let py = obj.py();
    let ma = py.import("numpy.ma")?;
    if !obj.is_instance(&ma.getattr("MaskedArray")?)? {
        return Ok(None);
    }
    let mask = ma.call_method1("getmaskarray", (obj,))?;
    let arr = mask
        .cast::<PyArrayDyn<bool>>()
        .map_err(|_| PyTypeError::new_err("the masked array's mask is not a boolean array"))?;
    let ro = arr.try_readonly()?;
    let v = ro.as_array();
    let mut out = vec![false; h * w];
    match v.ndim() {
        2 => {
            for (o, m) in out.iter_mut().zip(v.iter()) {
                *o = *m;
            }
        }
        3 => {
            for (o, lane) in out.iter_mut().zip(v.lanes(Axis(2))) {
                *o = lane.iter().any(|m| *m);
            }
        }
        _ => return Ok(None),
    }
    Ok(out.iter().any(|m| *m).then_some(out))
}

fn dtype_text(a: &Bound<'_, PyUntypedArray>) -> String {
    a.dtype()
        .str()
        .map_or_else(|_| "?".to_string(), |s| s.to_string())
}

fn shape_text(shape: &[usize]) -> String {
    let parts: Vec<String> = shape.iter().map(|n| n.to_string()).collect();
    match shape {
        [n] => format!("({n},)"),
        _ => format!("({})", parts.join(", ")),
    }
}

fn is<T: Element>(a: &Bound<'_, PyUntypedArray>) -> bool {
    a.dtype().is_equiv_to(&dtype::<T>(a.py()))
}

/// A read-only n-D view of `a` as `T` (whose dtype was checked).
fn view<'py, T: Element>(
    a: &Bound<'py, PyUntypedArray>,
) -> PyResult<numpy::PyReadonlyArrayDyn<'py, T>> {
    let arr = a
        .cast::<PyArrayDyn<T>>()
        .map_err(|_| PyTypeError::new_err("unexpected array type"))?;
    Ok(arr.try_readonly()?)
}

/// Grey values of float intensities in [0, 1] (Open3D's `RGBDImage.color`):
/// `round(255 x)`, exact for `k / 255`. One pass without branches (so that it
/// vectorises), the range checked on the way.
fn grey_from_float<T: Copy + Into<f64>>(v: ArrayViewD<'_, T>, out: &mut Vec<u8>) -> PyResult<()> {
    out.clear();
    let mut bad = false;
    let mut convert = |x: T| {
        let x: f64 = x.into();
        bad |= !(0.0..=1.0).contains(&x);
        // x ≥ 0: adding 0.5 and truncating is rounding (half away from zero).
        (x * 255.0 + 0.5) as u8
    };
    match v.as_slice() {
        Some(s) => out.extend(s.iter().map(|x| convert(*x))),
        None => out.extend(v.iter().map(|x| convert(*x))),
    }
    if bad {
        let x: f64 = v
            .iter()
            .map(|x| (*x).into())
            .find(|x: &f64| !(0.0..=1.0).contains(x))
            .unwrap_or(f64::NAN);
        return Err(PyValueError::new_err(format!(
            "float intensity must be in [0, 1] (grey / 255), got {x}"
        )));
    }
    Ok(())
}

/// The intensity plane: grey `(H, W)` uint8 (in place), colour `(H, W, 3|4)` uint8
/// converted with `0.299 R + 0.587 G + 0.114 B` rounded (the weights of
/// `read_sequence` and ecvo-io; alpha ignored), or float `(H, W)` in [0, 1]. Also
/// returns the mask of a masked array.
pub fn intensity<'py>(
    obj: &Bound<'py, PyAny>,
    channels: Channels,
    h: usize,
    w: usize,
    scratch: &mut Vec<u8>,
) -> PyResult<(Plane<'py, u8>, Option<Vec<bool>>)> {
    const WHAT: &str = "uint8 (grey (H, W) or colour (H, W, 3)) or float in [0, 1]";
    let arr = ndarray(obj, "intensity", WHAT)?;
    let mask = mask_of(&arr, h, w)?;
    let a = arr.cast::<PyUntypedArray>()?.clone();
    let shape = a.shape().to_vec();
    let grey = shape == [h, w];
    let colour = shape.len() == 3 && shape[..2] == [h, w] && (shape[2] == 3 || shape[2] == 4);
    if !grey && !colour {
        return Err(PyValueError::new_err(format!(
            "intensity must have shape ({h}, {w}) (grey) or ({h}, {w}, 3) (colour; \
             the camera's height, width), got {}",
            shape_text(&shape)
        )));
    }
    if is::<u8>(&a) {
        if grey {
            return Ok((
                Plane::Array(plane::<u8>(&arr, "intensity", "uint8", h, w)?),
                mask,
            ));
        }
        let ro = view::<u8>(&a)?;
        let v = ro.as_array();
        let (r, b) = match channels {
            Channels::Rgb => (0, 2),
            Channels::Bgr => (2, 0),
        };
        scratch.clear();
        scratch.reserve(h * w);
        match v.as_slice() {
            Some(s) => scratch.extend(
                s.chunks_exact(shape[2])
                    .map(|p| rgb_to_gray(p[r], p[1], p[b])),
            ),
            None => scratch.extend(
                v.lanes(Axis(2))
                    .into_iter()
                    .map(|p| rgb_to_gray(p[r], p[1], p[b])),
            ),
        }
        return Ok((Plane::Scratch, mask));
    }
    if grey && is::<f32>(&a) {
        grey_from_float(view::<f32>(&a)?.as_array(), scratch)?;
        return Ok((Plane::Scratch, mask));
    }
    if grey && is::<f64>(&a) {
        grey_from_float(view::<f64>(&a)?.as_array(), scratch)?;
        return Ok((Plane::Scratch, mask));
    }
    Err(PyTypeError::new_err(format!(
        "intensity must have dtype uint8 (grey or colour) or, grey, float32/float64 in \
         [0, 1], got {} with shape {}",
        dtype_text(&a),
        shape_text(&shape)
    )))
}

/// Raw depth of float metres: NaN and 0 are no measurement, others
/// `round(metres · depth_scale)` (exact for metres that came from raw / scale). One
/// pass without branches (so that it vectorises), the range checked on the way.
fn raw_from_metres<T: Copy + Into<f64>>(
    v: ArrayViewD<'_, T>,
    depth_scale: f64,
    out: &mut Vec<u16>,
) -> PyResult<()> {
    out.clear();
    let mut bad = false;
    let mut convert = |x: T| {
        let m: f64 = x.into();
        let r = m * depth_scale + 0.5;
        // Negative, infinite or beyond 65535 units (NaN compares false: no depth).
        bad |= m < 0.0 || r >= 65536.0;
        // Truncating r ≥ 0.5 is rounding; NaN casts to 0.
        r as u16
    };
    match v.as_slice() {
        Some(s) => out.extend(s.iter().map(|x| convert(*x))),
        None => out.extend(v.iter().map(|x| convert(*x))),
    }
    if bad {
        let m: f64 = v
            .iter()
            .map(|x| (*x).into())
            .find(|m: &f64| *m < 0.0 || m * depth_scale + 0.5 >= 65536.0)
            .unwrap_or(f64::NAN);
        return Err(PyValueError::new_err(format!(
            "float depth is metres (NaN or 0: no measurement) and must lie in \
             [0, {:.3}] at this camera's depth_scale {depth_scale} (65535 units); got {m}",
            u16::MAX as f64 / depth_scale
        )));
    }
    Ok(())
}

/// The depth plane: uint16 raw units (in place) or float32/float64 metres, each
/// `(H, W)`; the pixels in `mask`, and those masked in a masked depth array, lose
/// their depth.
pub fn depth<'py>(
    obj: &Bound<'py, PyAny>,
    depth_scale: f64,
    h: usize,
    w: usize,
    mut mask: Option<Vec<bool>>,
    scratch: &mut Vec<u16>,
) -> PyResult<Plane<'py, u16>> {
    const WHAT: &str = "uint16 (raw units) or float32 (metres)";
    let arr = ndarray(obj, "depth", WHAT)?;
    if let Some(m) = mask_of(&arr, h, w)? {
        match &mut mask {
            Some(mine) => mine.iter_mut().zip(m).for_each(|(a, b)| *a |= b),
            None => mask = Some(m),
        }
    }
    let a = arr.cast::<PyUntypedArray>()?.clone();
    if a.shape() != [h, w] {
        return Err(PyValueError::new_err(format!(
            "depth must have shape ({h}, {w}) (height, width of the camera), got {}",
            shape_text(a.shape())
        )));
    }
    let plane = if is::<u16>(&a) {
        let p = plane::<u16>(&arr, "depth", "uint16", h, w)?;
        if mask.is_none() {
            return Ok(Plane::Array(p));
        }
        let v = p.as_array();
        scratch.clear();
        scratch.extend(v.into_dimensionality::<Ix2>().expect("2-D").iter().copied());
        Plane::Scratch
    } else if is::<f32>(&a) {
        raw_from_metres(view::<f32>(&a)?.as_array(), depth_scale, scratch)?;
        Plane::Scratch
    } else if is::<f64>(&a) {
        raw_from_metres(view::<f64>(&a)?.as_array(), depth_scale, scratch)?;
        Plane::Scratch
    } else {
        return Err(PyTypeError::new_err(format!(
            "depth must have dtype uint16 (raw units, native byte order) or float32 / \
             float64 (metres), got {}",
            dtype_text(&a)
        )));
    };
    if let Some(m) = mask {
        for (d, masked) in scratch.iter_mut().zip(m) {
            if masked {
                *d = 0;
            }
        }
    }
    Ok(plane)
}
