//! The JavaScript surface of the retargeting module (`wasm-bindgen`): errors become thrown
//! `Error`s whose message names the problem. The package's `index.js` calls it.

use wasm_bindgen::prelude::*;

/// A BVH clip (text) retargeted onto the H-Anim body of a skeleton's `recipe` (the solver
/// module's `Skeleton.recipe`), foot contacts held unless `contacts` is false: `{frameTime,
/// frameCount, values: Float64Array (frameCount * dofCount), contacts, iterations, notes}`.
#[wasm_bindgen(js_name = retargetBvh)]
pub fn retarget_bvh(recipe: &str, bvh: &str, contacts: bool) -> Result<JsValue, JsError> {
    let r = crate::retarget_bvh(recipe, bvh, contacts).map_err(|e| JsError::new(&e))?;
    let out = js_sys::JSON::parse(&r.report.to_string())
        .map_err(|_| JsError::new("internal: invalid JSON output"))?;
    let set = |key: &str, value: JsValue| {
        js_sys::Reflect::set(&out, &key.into(), &value)
            .map(|_| ())
            .map_err(|_| JsError::new("internal: could not build the result"))
    };
    set("frameTime", r.frame_time.into())?;
    set("frameCount", (r.frame_count as f64).into())?;
    set(
        "values",
        js_sys::Float64Array::from(r.values.as_slice()).into(),
    )?;
    Ok(out)
}
