//! `jamkit check FAMILY`: the conformance kit on one registered family.

use anyhow::{Result, anyhow, bail};
use jamkit_registry as registry;
use std::panic::{self, AssertUnwindSafe};
use std::sync::{Arc, Mutex};

/// Run the kit on `family` (its example parameters unless `params` is
/// given) in `dim`, or in every dimension it claims; print what ran and
/// what was skipped, and fail with the kit's own message (the family, the
/// check, the numbers) on the first check that fails.
pub fn run(family: &str, params: Option<&str>, dim: Option<usize>) -> Result<()> {
    let info = registry::family_info(family)?;
    let index = registry::FAMILIES
        .iter()
        .position(|f| f.name == family)
        .expect("family_info found it");
    let params = params.unwrap_or(registry::EXAMPLES[index]);
    registry::params_from_ron(params).map_err(|e| anyhow!("--params {params}: {e}"))?;
    let dims = jamkit_kit::claimed_dims(family);
    let dims = match dim {
        Some(d) if dims.contains(&d) => vec![d],
        Some(d) => bail!(
            "--dim {d}: family `{family}` is defined in {}",
            registry::describe_dims(&info)
        ),
        None => dims,
    };
    for d in dims {
        println!("{family} in D = {d}, params {params}:");
        let checked = quietly(|| jamkit_kit::check_registered(family, d, params))
            .map_err(|message| anyhow!("{family} in D = {d} fails the kit: {message}"))?;
        for name in &checked.ran {
            println!("  ok       {name}");
        }
        for (name, why) in &checked.skipped {
            println!("  skipped  {name}: {why}");
        }
    }
    Ok(())
}

/// `f()`, with a failed assertion returned as its message instead of
/// printed by the panic hook.
fn quietly<T>(f: impl FnOnce() -> T) -> std::result::Result<T, String> {
    let message = Arc::new(Mutex::new(String::new()));
    let keep = Arc::clone(&message);
    let previous = panic::take_hook();
    panic::set_hook(Box::new(move |info| {
        let text = info
            .payload()
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| info.payload().downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        *keep.lock().unwrap() = text;
    }));
    let result = panic::catch_unwind(AssertUnwindSafe(f));
    panic::set_hook(previous);
    result.map_err(|_| message.lock().unwrap().clone())
}
