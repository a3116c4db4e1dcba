//! `import nephele`: nephele-runtime on numpy arrays — the shipped (or any) transport tables
//! evaluated at many points at once, and the phase models evaluated and sampled.
//!
//! Every answer comes from the Rust runtime itself (the batch of `nephele transport --points`,
//! `transport::evaluate_points`, rayon across the rows), so Python sees the renderer's numbers
//! bit for bit: the tables in f32 as in C and WGSL, the phase models in f64 (C and WGSL
//! evaluate them in f32; docs/integration.md gives the difference). Errors arrive as
//! `ValueError` with the runtime's message; arrays of the wrong shape or dtype are refused with
//! a message that names them.

use nephele_runtime::embedded::MIE_10UM;
use nephele_runtime::phase::named::{build, Model, Params, Preset};
use nephele_runtime::phase::TabulatedTable;
use nephele_runtime::transport::{
    column_names, evaluate_points, OwnedTables, Quantities, SlabPoint, TransportTables,
    POINT_COLUMNS,
};
use nephele_runtime::PhaseFunction;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Transport tables (a `.ntt`): T, c and sigma per order group of orders >= 2, and order 1,
/// at points of the canonical slab (docs/conventions.md).
///
/// Tables() holds the shipped Mie 10 um tables, Tables(path) a file, Tables.from_bytes(buf)
/// any buffer. evaluate(points) answers many points at once; domain says what the tables
/// cover; outside(points) flags points beyond their grid.
#[pyclass(frozen, module = "nephele")]
struct Tables {
    /// The file's bytes, loaded and checked once.
    owned: OwnedTables,
    /// Where they came from, for repr.
    source: String,
}

/// `e` as a Python ValueError with `what` before it.
fn value_error(what: &str, e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("{what}: {e}"))
}

impl Tables {
    fn with<R>(&self, f: impl FnOnce(&TransportTables) -> R) -> PyResult<R> {
        Ok(f(self.owned.tables()))
    }

    fn checked(bytes: Vec<u8>, source: String) -> PyResult<Self> {
        let owned = OwnedTables::from_bytes(bytes)
            .map_err(|e| value_error(&format!("transport tables {source}"), e))?;
        Ok(Tables { owned, source })
    }

    fn embedded() -> PyResult<Self> {
        let owned = OwnedTables::from_static(MIE_10UM)
            .map_err(|e| value_error("embedded transport tables", e))?;
        Ok(Tables {
            owned,
            source: "(embedded Mie 10 um)".into(),
        })
    }
}

/// The rows of a (N, 5) float32 or float64 array as f32, row-major.
fn point_rows(points: &Bound<'_, PyAny>) -> PyResult<Vec<f32>> {
    if let Ok(a) = points.downcast::<PyArray2<f64>>() {
        return rows_of(a.readonly(), |v| v as f32);
    }
    if let Ok(a) = points.downcast::<PyArray2<f32>>() {
        return rows_of(a.readonly(), |v| v);
    }
    Err(PyTypeError::new_err(format!(
        "points: a 2-D float32 or float64 numpy array of rows ({POINT_NAMES}) expected, got {}",
        describe(points)
    )))
}

/// The columns of a row of points, for messages.
const POINT_NAMES: &str = "t, mu_L, depth, mu_V, psi_V (radians)";

/// The values of a 2-D array of rows of points as f32 (`to`), its shape checked.
fn rows_of<T: numpy::Element + Copy>(
    r: numpy::PyReadonlyArray2<'_, T>,
    to: impl Fn(T) -> f32,
) -> PyResult<Vec<f32>> {
    let shape = r.shape();
    if shape.len() != 2 || shape[1] != POINT_COLUMNS {
        return Err(value_error(
            "points",
            format!("shape {}, expected (N, 5): {POINT_NAMES}", tuple(shape)),
        ));
    }
    Ok(r.as_array().iter().map(|&v| to(v)).collect())
}

/// A shape as Python prints it: (3, 4), (5,).
fn tuple(shape: &[usize]) -> String {
    let parts: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    if parts.len() == 1 {
        format!("({},)", parts[0])
    } else {
        format!("({})", parts.join(", "))
    }
}

/// "numpy array of dtype X and shape Y" or the Python type's name.
fn describe(x: &Bound<'_, PyAny>) -> String {
    if let Ok(a) = x.downcast::<numpy::PyUntypedArray>() {
        return format!(
            "a numpy array of dtype {} and shape {}",
            a.dtype(),
            tuple(a.shape())
        );
    }
    x.get_type()
        .name()
        .map_or("an unknown object".into(), |n| n.to_string())
}

#[pymethods]
impl Tables {
    /// Tables(path=None): the `.ntt` at `path`, or the shipped Mie 10 µm tables the runtime
    /// embeds (what `nephele render` uses).
    #[new]
    #[pyo3(signature = (path=None))]
    fn new(path: Option<std::path::PathBuf>) -> PyResult<Self> {
        match path {
            None => Self::embedded(),
            Some(p) => {
                let bytes = std::fs::read(&p).map_err(|e| {
                    value_error(&format!("cannot read tables '{}'", p.display()), e)
                })?;
                Self::checked(bytes, format!("'{}'", p.display()))
            }
        }
    }

    /// Tables.from_bytes(data): tables from the bytes of a `.ntt` in any buffer: bytes,
    /// bytearray, memoryview, a uint8 numpy array, or anything bytes() accepts. The bytes are
    /// copied.
    #[staticmethod]
    fn from_bytes(data: &Bound<'_, PyAny>) -> PyResult<Self> {
        let bytes = if let Ok(b) = data.downcast::<pyo3::types::PyBytes>() {
            b.as_bytes().to_vec()
        } else if let Ok(a) = data.downcast::<PyArray1<u8>>() {
            a.readonly().as_array().to_vec()
        } else {
            // bytes(n) would make n zero bytes of an int: only buffers are taken.
            let buffer = !data.is_instance_of::<pyo3::types::PyInt>();
            let builtins = data.py().import("builtins")?;
            let made = if buffer {
                builtins.getattr("bytes").and_then(|b| b.call1((data,)))
            } else {
                Err(PyTypeError::new_err("an int"))
            };
            let b = made.map_err(|_| {
                PyTypeError::new_err(format!(
                    "data: the bytes of a .ntt expected (bytes, bytearray, memoryview, a uint8 \
                     array), got {}",
                    describe(data)
                ))
            })?;
            b.downcast::<pyo3::types::PyBytes>()?.as_bytes().to_vec()
        };
        Self::checked(bytes, "(bytes)".into())
    }

    /// repr(): where the tables came from.
    fn __repr__(&self) -> String {
        format!("nephele.Tables({})", self.source)
    }

    /// The number of order groups.
    #[getter]
    fn groups(&self) -> PyResult<usize> {
        self.with(|t| t.groups())
    }

    /// The first scattering order of each group.
    #[getter]
    fn group_first_orders(&self) -> PyResult<Vec<f32>> {
        self.with(|t| {
            (0..t.groups())
                .filter_map(|g| t.group_first_order(g))
                .collect()
        })
    }

    /// {"t": (lo, hi), "mu_l": (lo, hi), "mean_cosine": g}: the grid the tables were fitted
    /// on, and g of their phase function. Past the thickest slab the tables continue by
    /// diffusion theory; below the thinnest they hold the grid's end; below the lowest sun
    /// they hold T/mu_L (outside() flags such points).
    #[getter]
    fn domain<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (d, g) = self.with(|t| (t.domain(), t.mean_cosine()))?;
        let out = PyDict::new(py);
        out.set_item("t", d.thickness)?;
        out.set_item("mu_l", d.mu_l)?;
        out.set_item("mean_cosine", g)?;
        Ok(out)
    }

    /// outside(points) -> uint8 array of N flags: 0 within the grid, else a sum of 1 (t past
    /// the thickest slab), 2 (t below the thinnest) and 4 (the sun below the lowest). points
    /// as for evaluate; a point outside the slab raises ValueError.
    fn outside<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<u8>>> {
        let rows = point_rows(points)?;
        let d = self.with(|t| t.domain())?;
        let mut flags = Vec::with_capacity(rows.len() / POINT_COLUMNS);
        for (i, r) in rows.chunks_exact(POINT_COLUMNS).enumerate() {
            let at = SlabPoint::from_row(&[r[0], r[1], r[2], r[3], r[4]]);
            at.check()
                .map_err(|e| value_error("outside", format!("row {i}: {e}")))?;
            flags.push(d.outside(&at).bits(&d) as u8);
        }
        Ok(PyArray1::from_vec(py, flags))
    }

    /// evaluate(points, collector=False) → float32 array.
    ///
    /// points: (N, 5) float32 or float64, rows of t (mfp), mu_L, depth below the lit face (mfp),
    /// mu_V (> 0: light going up), psi_V (radians, from the sun's horizontal travel). Returns
    /// (N, 1 + G): order 1 then T of each group (1/sr), or with collector=True (N, 1 + 4G):
    /// order 1 then T, c_x, c_z, sigma of each group (mfp). A point outside the slab (t <= 0,
    /// mu_L outside (0, 1], depth outside [0, t], |mu_V| > 1, NaN, inf) raises ValueError
    /// naming its row and coordinate. The rows are shared among threads; the answers do not
    /// depend on how many.
    #[pyo3(signature = (points, collector=false))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
        collector: bool,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let rows = point_rows(points)?;
        let what = if collector {
            Quantities::WithCollector
        } else {
            Quantities::Transport
        };
        let n = rows.len() / POINT_COLUMNS;
        let (width, out) = py.allow_threads(|| {
            self.with(|t| {
                let width = what.columns(t.groups());
                let mut out = vec![0.0f32; n * width];
                let done = evaluate_points(t, &rows, what, &mut out).map(|_| ());
                (width, done.map(|()| out))
            })
        })?;
        let out = out.map_err(|e| value_error("evaluate", e))?;
        let flat = PyArray1::from_vec(py, out);
        flat.reshape([n, width])
    }

    /// The names of evaluate's columns: "order1", "T_2", "T_3-4", … (with collector=True
    /// also "c_x_…", "c_z_…", "sigma_…").
    #[pyo3(signature = (collector=false))]
    fn columns(&self, collector: bool) -> PyResult<Vec<String>> {
        let what = if collector {
            Quantities::WithCollector
        } else {
            Quantities::Transport
        };
        self.with(|t| column_names(t, what))
    }
}

/// A phase model from its name and keyword parameters: the runtime's table of models
/// (`phase::named`) with its checks, or a table p(θ) for `tabulated`.
fn phase_model(
    model: &str,
    kw: Option<&Bound<'_, PyDict>>,
) -> PyResult<Box<dyn PhaseFunction<f64> + Send + Sync>> {
    let m =
        Model::from_name(model).map_err(|e| PyValueError::new_err(e.naming(model).to_string()))?;
    if m == Model::Tabulated {
        return tabulated(kw);
    }
    let mut p = Params::default();
    for (k, v) in kw.map(|d| d.iter()).into_iter().flatten() {
        let k: String = k.extract()?;
        if k == "preset" {
            let name: String = v.extract()?;
            p.preset = Some(
                Preset::from_name(&name)
                    .map_err(|e| PyValueError::new_err(e.naming(&name).to_string()))?,
            );
            continue;
        }
        let v = v
            .extract::<f64>()
            .map_err(|_| PyTypeError::new_err(format!("{model}: {k} must be a number")))?;
        p.set(m, &k, v).map_err(|_| {
            PyValueError::new_err(format!(
                "model {} does not take {k} (it takes: {})",
                m.name(),
                m.takes().join(", ")
            ))
        })?;
    }
    let (named, _) = build::<f64>(m, &p).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(Box::new(named))
}

/// `tabulated` from its keyword arrays theta (degrees, 0 to 180) and p (1/sr, any
/// normalisation).
fn tabulated(
    kw: Option<&Bound<'_, PyDict>>,
) -> PyResult<Box<dyn PhaseFunction<f64> + Send + Sync>> {
    if let Some(k) = kw.into_iter().flat_map(|d| d.keys()).find(|k| {
        k.extract::<String>()
            .is_ok_and(|k| k != "theta" && k != "p")
    }) {
        return Err(PyValueError::new_err(format!(
            "model tabulated does not take {k} (it takes: theta, p)"
        )));
    }
    let array = |name: &str| -> PyResult<Vec<f64>> {
        let item = kw
            .and_then(|d| d.get_item(name).ok().flatten())
            .ok_or_else(|| {
                PyValueError::new_err(format!(
                "tabulated needs {name}= (theta: angles in degrees from 0 to 180, p: the phase \
                 function there, 1/sr, any normalisation)"
            ))
            })?;
        values_1d(&format!("tabulated: {name}"), &item)
    };
    let table = TabulatedTable::<f64>::from_phase(&array("theta")?, &array("p")?)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(Box::new(table))
}

/// A 1-D float64 array's values, or an error naming `what`.
fn values_1d(what: &str, x: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    if let Ok(a) = x.downcast::<PyArray1<f64>>() {
        return Ok(a.readonly().as_array().to_vec());
    }
    if let Ok(a) = x.downcast::<PyArray1<f32>>() {
        return Ok(a
            .readonly()
            .as_array()
            .iter()
            .map(|&v| f64::from(v))
            .collect());
    }
    Err(PyTypeError::new_err(format!(
        "{what}: a 1-D float32 or float64 numpy array expected, got {}",
        describe(x)
    )))
}

/// phase_eval(model, mu, **params) → p(mu) (1/sr), float64; mu = cos of the scattering angle
/// (1 forward). Models (kebab- or snake_case) and their parameters: hg (g), two_term_hg (g, g2,
/// w: w HG(g) + (1 - w) HG(g2)), cornette_shanks (g), draine (g, alpha), hg_draine (diameter in
/// um, 0 < d <= 50, with preset = "jendersie_deon" or "nephele"; or g_hg, g_d, alpha, w_d),
/// rayleigh, reynolds_mccormick (g, alpha), schlick (k), vmf (kappa), xlf (g), tabulated (theta:
/// angles in degrees from 0 to 180, p: the phase function there, 1/sr, any normalisation;
/// normalised here). The ranges are those of nephele's configs and of C.
#[pyfunction]
#[pyo3(signature = (model, mu, **params))]
fn phase_eval<'py>(
    py: Python<'py>,
    model: &str,
    mu: &Bound<'py, PyAny>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = phase_model(model, params)?;
    map_values(py, ("mu", mu, (-1.0, 1.0)), |x| m.eval(x))
}

/// phase_sample(model, xi, **params) → cosines drawn by the model's exact sampler at the
/// uniform numbers xi in [0, 1) (float64); the same models and parameters as phase_eval.
#[pyfunction]
#[pyo3(signature = (model, xi, **params))]
fn phase_sample<'py>(
    py: Python<'py>,
    model: &str,
    xi: &Bound<'py, PyAny>,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = phase_model(model, params)?;
    map_values(py, ("xi", xi, (0.0, 1.0)), |x| m.sample_mu(x))
}

/// `f` of every value of the 1-D array `x` (named `what`, each within `range`), without the GIL.
fn map_values<'py>(
    py: Python<'py>,
    (what, x, (lo, hi)): (&str, &Bound<'py, PyAny>, (f64, f64)),
    f: impl Fn(f64) -> f64 + Send + Sync,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let x = values_1d(what, x)?;
    if let Some(bad) = x.iter().find(|v| !(lo..=hi).contains(*v)) {
        return Err(PyValueError::new_err(format!(
            "{what}: {bad} is outside [{lo}, {hi}]"
        )));
    }
    let out: Vec<f64> = py.allow_threads(|| x.iter().map(|&v| f(v)).collect());
    Ok(PyArray1::from_vec(py, out))
}

/// nephele-runtime from Python: cloud transport tables and phase models of water droplets on
/// numpy arrays.
///
/// Tables: the transport tables (T, c, sigma per order group, order 1) at many points of the
/// canonical slab at once; phase_eval and phase_sample: the phase models, evaluated and
/// sampled exactly. psi_V is in radians here, as in C and WGSL (nephele transport takes
/// degrees, as --psi-deg). docs/integration.md in the repository has the details.
#[pymodule]
fn nephele(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Tables>()?;
    m.add_function(wrap_pyfunction!(phase_eval, m)?)?;
    m.add_function(wrap_pyfunction!(phase_sample, m)?)?;
    m.add("__version__", nephele_runtime::VERSION)?;
    Ok(())
}
