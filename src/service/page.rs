//! The job page (`GET /v1/jobs/{id}` with `Accept: text/html`): one self-contained HTML
//! document, no framework and nothing fetched from elsewhere, so it works offline. It
//! shows the status and progress (reloading every few seconds while the job is not
//! finished), the advice on a case outside the validated envelope (from submission on), the load
//! plot and the flow pictures with a time slider, the pressure along each body's surface
//! under them following the same slider, all drawn by the service's own SVG routes.
//!
//! Each picture's `<img>` gets `data-rendered="yes"` once it has loaded with a non-zero
//! size (`"no"` on an error), which is what the browser test reads.

use super::store::JobRow;
use serde_json::Value;
use std::fmt::Write as _;

/// Seconds between reloads while a job is queued or running.
const REFRESH_S: u32 = 5;

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

const STYLE: &str = "body{font-family:sans-serif;margin:1.5em;max-width:1300px;color:#222}\
img{max-width:100%;border:1px solid #ddd}progress{width:30em}\
table{border-collapse:collapse}td{padding:2px 12px 2px 0}\
pre{background:#f6f6f6;padding:8px;overflow:auto;max-height:20em}\
#advice{background:#fff6d5;padding:6px 6px 6px 24px}";

const SCRIPT: &str = r#"
function watch(img) {
  const mark = () => { img.dataset.rendered = img.naturalWidth > 0 ? "yes" : "no"; };
  img.addEventListener("load", mark);
  img.addEventListener("error", () => { img.dataset.rendered = "no"; });
  if (img.complete) mark();
}
document.querySelectorAll("img").forEach(watch);
const flow = document.getElementById("flow");
if (flow) {
  const times = JSON.parse(flow.dataset.times);
  const slider = document.getElementById("time");
  const field = document.getElementById("field");
  const label = document.getElementById("time-label");
  const show = () => {
    const t = times[Number(slider.value)];
    label.textContent = "t = " + (t * 1e3).toFixed(3) + " ms";
    flow.dataset.rendered = "";
    flow.src = flow.dataset.base + "?time=" + t + "&field=" + field.value;
    document.querySelectorAll("img.surface").forEach((img) => {
      img.dataset.rendered = "";
      img.src = img.dataset.base + "&time=" + t;
    });
  };
  slider.addEventListener("input", show);
  field.addEventListener("change", show);
}
"#;

/// `text` as a URL query value: unreserved characters kept, every other byte of its UTF-8
/// as `%XX`.
fn query_value(text: &str) -> String {
    text.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// The page of job `row` (`json`: its record as the API serves it; `advice`: what
/// `mpsfsi check` advises its case; `bodies`: the names of its bodies, each drawn with
/// the pressure along its surface under the flow; `snapshot_times`: the snapshots
/// written so far).
pub fn job_page(
    row: &JobRow,
    json: &Value,
    advice: &[String],
    bodies: &[String],
    snapshot_times: &[f64],
) -> String {
    let base = format!("/v1/jobs/{}", row.id);
    let name = escape(&row.name);
    let status = row.status.as_str();
    let fraction = json["progress"]["fraction"].as_f64().unwrap_or(0.0);
    let mut html = String::new();
    html.push_str("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n");
    let _ = writeln!(html, "<title>{name}: {status}</title>");
    if !row.status.is_finished() {
        let _ = writeln!(
            html,
            "<meta http-equiv=\"refresh\" content=\"{REFRESH_S}\">"
        );
    }
    let _ = writeln!(html, "<style>{STYLE}</style></head><body>");
    let _ = writeln!(html, "<h1>{name}</h1>");
    let _ = writeln!(
        html,
        "<p id=\"status\">Status: <b>{status}</b>{}</p>",
        row.reason
            .as_deref()
            .map(|r| format!(" ({})", escape(r)))
            .unwrap_or_default()
    );
    if !advice.is_empty() {
        html.push_str("<ul id=\"advice\">");
        for line in advice {
            let _ = write!(html, "<li>{}</li>", escape(line));
        }
        html.push_str("</ul>\n");
    }
    // a ladder's coarser parts run beside the user's level, on whichever workers are free
    let ladder = match row.uncertainty {
        true => {
            let coarser = (row.parts - 1).max(0);
            format!(
                "; error bars: {} of {coarser} coarser runs ended",
                row.part.min(coarser)
            )
        }
        false => String::new(),
    };
    let _ = writeln!(
        html,
        "<p id=\"progress\"><progress value=\"{fraction:.4}\" max=\"1\"></progress> {:.1} %: t = {:.4} ms of {:.4} ms, step {}{ladder}</p>",
        100.0 * fraction,
        row.simulated_time * 1e3,
        row.end_time * 1e3,
        row.step
    );
    let _ = writeln!(
        html,
        "<table><tr><td>job</td><td>{}</td></tr><tr><td>created</td><td>{}</td></tr>\
         <tr><td>started</td><td>{}</td></tr><tr><td>finished</td><td>{}</td></tr>\
         <tr><td>particles</td><td>{}</td></tr></table>",
        row.id,
        escape(&row.created_at),
        escape(row.started_at.as_deref().unwrap_or("")),
        escape(row.finished_at.as_deref().unwrap_or("")),
        row.particles.map(|p| p.to_string()).unwrap_or_default()
    );
    html.push_str("<h2>Loads</h2>\n");
    let _ = writeln!(
        html,
        "<p><a href=\"{base}/loads\">JSON</a> · CSV with <code>Accept: text/csv</code></p>\
         <img id=\"loads\" src=\"{base}/loads.svg\" alt=\"load history\">"
    );
    html.push_str("<h2>Flow</h2>\n");
    match snapshot_times.last() {
        None => html.push_str(
            "<p id=\"no-flow\">No snapshots yet (or the case sets <code>output.snapshot_interval</code> to \"none\").</p>\n",
        ),
        Some(last) => {
            let times = serde_json::to_string(snapshot_times).unwrap_or_else(|_| "[]".into());
            let _ = writeln!(
                html,
                "<p><label>field <select id=\"field\">\
                 <option value=\"pressure\">pressure</option><option value=\"speed\">speed</option>\
                 <option value=\"velocity_x\">velocity x</option><option value=\"velocity_y\">velocity y</option>\
                 </select></label> <label>time <input id=\"time\" type=\"range\" min=\"0\" max=\"{}\" value=\"{}\"></label> \
                 <span id=\"time-label\">t = {:.3} ms</span></p>",
                snapshot_times.len() - 1,
                snapshot_times.len() - 1,
                last * 1e3
            );
            let _ = writeln!(
                html,
                "<img id=\"flow\" alt=\"flow picture\" data-base=\"{base}/snapshot.svg\" data-times=\"{}\" src=\"{base}/snapshot.svg?time={last}&amp;field=pressure\">",
                escape(&times)
            );
            for (k, body) in bodies.iter().enumerate() {
                let surface = format!("{base}/surface.svg?body={}", query_value(body));
                let _ = writeln!(
                    html,
                    "<br><img class=\"surface\" id=\"surface-{k}\" alt=\"pressure along {}\" data-base=\"{}\" src=\"{}&amp;time={last}\">",
                    escape(body),
                    escape(&surface),
                    escape(&surface)
                );
            }
        }
    }
    if let Some(summary) = json.get("summary").filter(|s| !s.is_null()) {
        let text = serde_json::to_string_pretty(summary).unwrap_or_default();
        let _ = writeln!(html, "<h2>Summary</h2>\n<pre>{}</pre>", escape(&text));
    }
    let _ = writeln!(html, "<script>{SCRIPT}</script>\n</body></html>");
    html
}

/// The sign-in form ([`super::sign_in`]): the token, posted with `next`, the page to go to
/// afterwards; `refused` when the token just posted was wrong; `token_needed` false
/// when the server has no token (then nothing needs one).
pub fn sign_in_form(action: &str, next: &str, token_needed: bool, refused: bool) -> String {
    let mut html = String::new();
    html.push_str("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n");
    let _ = writeln!(
        html,
        "<title>Sign in: mpsfsi</title><style>{STYLE}</style></head><body>\n<h1>Sign in</h1>"
    );
    if !token_needed {
        let _ = writeln!(
            html,
            "<p id=\"no-token\">This server has no token: nothing needs signing in. \
             <a href=\"{}\">Go on</a>.</p>",
            escape(next)
        );
    }
    if refused {
        html.push_str("<p id=\"refused\"><b>That is not the token of this server.</b></p>\n");
    }
    let _ = writeln!(
        html,
        "<form method=\"post\" action=\"{}\">\
         <label>Token <input type=\"password\" name=\"token\" autocomplete=\"current-password\" required autofocus></label>\
         <input type=\"hidden\" name=\"next\" value=\"{}\"> <button type=\"submit\">Sign in</button></form>\n\
         <p>The browser then keeps a cookie that lets it read pages, pictures and results; \
         submitting, cancelling and deleting jobs still need the token in an \
         <code>Authorization: Bearer</code> header.</p>\n</body></html>",
        escape(action),
        escape(next)
    );
    html
}

/// The 401 of a page requested without the token or a sign-in: a link to the sign-in
/// form that comes back to `target` (a path of this service, with its query).
pub fn sign_in_needed(sign_in: &str, target: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n\
         <title>Sign in needed: mpsfsi</title><style>{STYLE}</style></head><body>\n\
         <h1>Sign in needed</h1>\n<p>This server needs its token. \
         <a id=\"sign-in\" href=\"{}\">Sign in</a> to open this page.</p>\n</body></html>\n",
        escape(&format!("{sign_in}?next={}", query_value(target)))
    )
}
