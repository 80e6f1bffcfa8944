//! The report as one HTML page: figures in text and tables, charts as
//! inline SVG drawn with plotters; no script, no style sheet, no font or
//! image from anywhere else, so it opens from a USB stick on any machine.

use std::fmt::Write as _;

use plotters::coord::types::RangedCoordu32;
use plotters::prelude::*;

use super::Report;

/// Where the installed package keeps `library check`'s explanation (a
/// file on the kiosk: nothing is fetched from the network).
const LIBRARY_CHECK_DOC: &str =
    "file:///usr/share/doc/marionette/docs/exhibit.md#marionette-library-check-dir---json";

const BLUE: RGBColor = RGBColor(52, 101, 164);
const ORANGE: RGBColor = RGBColor(222, 120, 31);

/// Text made safe inside HTML (and SVG) text and attributes.
#[must_use]
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// A bar chart of one or two series over `labels` (the second drawn in
/// orange beside the first), as SVG text.
fn bars(title: &str, labels: &[String], series: &[(&str, &[u64])], size: (u32, u32)) -> String {
    let mut svg = String::new();
    // Each category takes one segment a series, and one more between
    // categories when there are several series.
    let k = series.len().max(1) as u32;
    let group = if k > 1 { k + 1 } else { 1 };
    // (A segmented range of 0..n has n + 1 segments: the last is left out.)
    let n = (labels.len().max(1) as u32 * group)
        .saturating_sub(1)
        .max(1);
    let top = series
        .iter()
        .flat_map(|(_, v)| v.iter().copied())
        .max()
        .unwrap_or(0)
        .max(1);
    let drawn = (|| -> Result<(), Box<dyn std::error::Error + '_>> {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(48)
            .build_cartesian_2d((0u32..n).into_segmented(), 0u64..top + top / 10 + 1)?;
        let label = |v: &SegmentValue<u32>| match v {
            SegmentValue::CenterOf(i) | SegmentValue::Exact(i) if i % group == 0 => labels
                .get((i / group) as usize)
                .cloned()
                .unwrap_or_default(),
            _ => String::new(),
        };
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(n as usize)
            .x_label_formatter(&label)
            .x_label_style(("sans-serif", 12).into_font())
            .y_label_style(("sans-serif", 12).into_font())
            .draw()?;
        for (s, (name, values)) in series.iter().enumerate() {
            let colour = if s == 0 { BLUE } else { ORANGE };
            let drawn = chart.draw_series(values.iter().enumerate().map(|(i, v)| {
                let x = i as u32 * group + s as u32;
                let mut bar = Rectangle::new(
                    [
                        (SegmentValue::Exact(x), 0u64),
                        (SegmentValue::Exact(x + 1), *v),
                    ],
                    colour.filled(),
                );
                bar.set_margin(0, 0, 2, 2);
                bar
            }))?;
            if k > 1 {
                drawn.label(*name).legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 10, y + 5)], colour.filled())
                });
            }
        }
        if k > 1 {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .label_font(("sans-serif", 12))
                .draw()?;
        }
        root.present()?;
        Ok(())
    })();
    if let Err(e) = drawn {
        tracing::warn!(chart = title, error = %e, "a chart could not be drawn");
    }
    svg
}

/// Where fingers land: the grid's cells shaded by their counts, as SVG.
fn heat_map(heat: &[Vec<u64>], size: (u32, u32)) -> String {
    let mut svg = String::new();
    let rows = heat.len().max(1) as u32;
    let cols = heat.first().map_or(1, Vec::len).max(1) as u32;
    let top = heat.iter().flatten().copied().max().unwrap_or(0).max(1) as f64;
    let drawn = (|| -> Result<(), Box<dyn std::error::Error + '_>> {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart: ChartContext<'_, _, Cartesian2d<RangedCoordu32, RangedCoordu32>> =
            ChartBuilder::on(&root)
                .caption("Where fingers land on the screen", ("sans-serif", 18))
                .margin(12)
                .build_cartesian_2d(0u32..cols, rows..0u32)?;
        chart.draw_series(heat.iter().enumerate().flat_map(|(y, row)| {
            row.iter().enumerate().map(move |(x, n)| {
                let a = (*n as f64 / top).sqrt();
                let shade = RGBColor(
                    (255.0 - a * 40.0) as u8,
                    (255.0 - a * 200.0) as u8,
                    (255.0 - a * 230.0) as u8,
                );
                Rectangle::new(
                    [(x as u32, y as u32), (x as u32 + 1, y as u32 + 1)],
                    shade.filled(),
                )
            })
        }))?;
        chart.draw_series(heat.iter().enumerate().flat_map(|(y, row)| {
            row.iter().enumerate().map(move |(x, _)| {
                Rectangle::new(
                    [(x as u32, y as u32), (x as u32 + 1, y as u32 + 1)],
                    RGBColor(220, 220, 220).stroke_width(1),
                )
            })
        }))?;
        root.present()?;
        Ok(())
    })();
    if let Err(e) = drawn {
        tracing::warn!(error = %e, "the heat map could not be drawn");
    }
    svg
}

fn date(ms: Option<i64>) -> String {
    ms.map_or_else(
        || "-".to_owned(),
        |ms| {
            let (y, m, d) = crate::app::visits::writer::civil(ms.div_euclid(86_400_000));
            format!("{y:04}-{m:02}-{d:02} (UTC)")
        },
    )
}

/// The whole page.
#[must_use]
pub fn page(r: &Report) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>marionette: what visitors do</title>\
         <style>td, th {{ padding: 2px 12px; text-align: left }} tr:nth-child(even) {{ background: #f2f2f2 }}</style>\
         </head><body style=\"font-family: sans-serif; max-width: 1100px; margin: 2em auto; color: #222\">\
         <h1>What visitors do at the table</h1>\
         <p>From the visits record <code>{}</code>: {} to {}{}.</p>",
        escape(&r.db),
        date(r.first_ms),
        date(r.last_ms),
        if r.since_ms.is_some() {
            ", the window asked for"
        } else {
            ", all of it"
        }
    );
    let _ = write!(
        h,
        "<h2>For the curator</h2><table id=\"figures\" style=\"border-collapse: collapse\">\
         <tr><td>Sessions</td><td id=\"sessions\">{}</td></tr>\
         <tr><td>Dwell time (mean / median / 90th percentile)</td><td>{:.0} s / {:.0} s / {:.0} s</td></tr>\
         <tr><td>Sessions that started an action</td><td id=\"with-action\">{} ({:.0} %)</td></tr>\
         <tr><td>Actions started / finished</td><td id=\"actions\">{} / {}</td></tr>\
         <tr><td>Most fingers at once</td><td id=\"peak\">{}</td></tr>\
         <tr><td>Fingers that landed / on a body part / on the floor (camera)</td><td id=\"touches\">{} / {} / {}</td></tr>\
         <tr><td>Drags that came near an action and started nothing</td><td id=\"near-misses\">{}</td></tr>\
         </table>",
        r.sessions,
        r.dwell_mean_s,
        r.dwell_median_s,
        r.dwell_p90_s,
        r.sessions_with_action,
        r.share_with_action * 100.0,
        r.actions_started,
        r.actions_finished,
        r.peak_fingers,
        r.touches,
        r.grabs,
        r.camera_moves,
        r.near_misses
    );
    let hours: Vec<String> = (0..24).map(|h| format!("{h}")).collect();
    h.push_str(&bars(
        "Sessions by hour of day (local time)",
        &hours,
        &[("sessions", &r.sessions_per_hour)],
        (1000, 300),
    ));
    let (days, per_day): (Vec<String>, Vec<u64>) = r
        .sessions_per_day
        .iter()
        .rev()
        .take(62)
        .rev()
        .map(|(d, n)| (d.get(5..).unwrap_or(d).to_owned(), *n))
        .unzip();
    h.push_str(&bars(
        "Sessions by day (the last 62 shown)",
        &days,
        &[("sessions", &per_day)],
        (1000, 320),
    ));
    let (bins, dwell): (Vec<String>, Vec<u64>) = r.dwell_bins.iter().cloned().unzip();
    h.push_str(&bars(
        "How long visitors stay",
        &bins,
        &[("sessions", &dwell)],
        (1000, 300),
    ));
    let (fingers, at_once): (Vec<String>, Vec<u64>) = r
        .fingers_at_once
        .iter()
        .map(|(f, n)| (format!("{f}"), *n))
        .unzip();
    h.push_str(&bars(
        "Most fingers at once (sessions)",
        &fingers,
        &[("sessions", &at_once)],
        (1000, 260),
    ));

    h.push_str("<h2>For the exhibit builder</h2>");
    if r.advice.is_empty() {
        h.push_str("<p>No action is often tried and not started.</p>");
    } else {
        h.push_str("<ul id=\"advice\">");
        for a in &r.advice {
            let _ = write!(h, "<li>{}</li>", escape(a));
        }
        let _ = write!(
            h,
            "</ul><p>What the library's own takes start, action by action: \
             <code>marionette library check LIBRARY</code>, explained in \
             <a href=\"{LIBRARY_CHECK_DOC}\">the exhibit builder's guide</a> (installed with the package).</p>"
        );
    }
    h.push_str(
        "<table id=\"actions-table\" style=\"border-collapse: collapse\"><tr><th>action</th><th>started</th>\
         <th>finished</th><th>cancelled</th><th>near misses</th><th>held back by its shape</th></tr>",
    );
    for a in &r.actions {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(&a.action),
            a.started,
            a.finished,
            a.cancelled,
            a.near_misses,
            a.held_by_cost
        );
    }
    h.push_str("</table>");
    let names: Vec<String> = r.actions.iter().map(|a| a.action.clone()).collect();
    let started: Vec<u64> = r.actions.iter().map(|a| a.started).collect();
    let near: Vec<u64> = r.actions.iter().map(|a| a.near_misses).collect();
    h.push_str(&bars(
        "Actions started (blue) and drags that came nearest to them and started nothing (orange)",
        &names,
        &[("started", &started), ("near misses", &near)],
        (1000, 340),
    ));
    let parts: Vec<String> = r.parts.iter().map(|p| p.part.clone()).collect();
    let grabs: Vec<u64> = r.parts.iter().map(|p| p.grabs).collect();
    h.push_str(&bars(
        "Body parts grabbed",
        &parts,
        &[("grabs", &grabs)],
        (1000, 320),
    ));
    h.push_str(&heat_map(&r.heat, (960, 580)));
    h.push_str("<p>Made by <code>marionette report</code>; the figures are also in <code>report.json</code> beside this page.</p></body></html>\n");
    h
}
