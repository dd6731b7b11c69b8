//! An SVG picture of a simulated run: the arena, the true path and the
//! firmware's estimated (and dead-reckoned) paths, with start and end
//! poses. North (x) points up, east (y) to the right, 1 px per mm.

use super::arena::Arena;
use super::body::PoseF64;
use crate::model::lidar::LidarMount;
use std::fmt::Write;
use std::string::String;

/// One path to draw.
pub struct Track<'a> {
    pub label: &'a str,
    /// CSS colour.
    pub color: &'a str,
    pub dashed: bool,
    pub poses: &'a [PoseF64],
}

/// A stretch of a path drawn over the tracks, without start or end marks:
/// what a replay reported when (a colour per hypothesis). Stretches of one
/// label share one legend row.
pub struct Stretch<'a> {
    pub label: String,
    /// CSS colour.
    pub color: &'a str,
    pub dashed: bool,
    pub poses: &'a [PoseF64],
}

const MARGIN: f64 = 40.0;
const LEGEND_ROW: f64 = 18.0;
/// The widest a character of the 12 px sans-serif text runs, px (0.62 em:
/// the widest common sans-serif faces' average for lower-case text with
/// capitals and digits; a text's room is its characters times this).
pub const CHAR_PX: f64 = 7.5;
/// Where a legend row's text starts, right of its line sample, px.
const LEGEND_TEXT_X: f64 = MARGIN + 38.0;
/// Length of the heading arrow at the end of a track, px (= mm).
const ARROW: f64 = 40.0;

/// One lidar reading drawn as a line from the lidar to where its beam ended
/// (mm, x north, y east), with a dot at the end.
#[derive(Clone, Copy, PartialEq, Debug)]
pub struct Ray<'a> {
    pub from: (f64, f64),
    pub to: (f64, f64),
    pub color: &'a str,
}

impl<'a> Ray<'a> {
    /// A reading of the lidar at `mount` on the body at `pose`, from the
    /// lidar to where the beam ended ([`LidarMount::beam_f64`]: `distance_mm`
    /// is the lidar model's distance from the reference point along the beam).
    pub fn of_reading(pose: &PoseF64, mount: &LidarMount, distance_mm: f64, color: &'a str) -> Ray<'a> {
        let (from, to) = mount.beam_f64(pose.x, pose.y, pose.theta, distance_mm);
        Ray { from, to, color }
    }
}

/// Renders the arena and the tracks as a standalone SVG document.
pub fn render(arena: &Arena, tracks: &[Track<'_>], title: &str) -> String {
    render_with_rays(arena, tracks, &[], title)
}

/// [`render`] with lidar readings drawn under the tracks.
pub fn render_with_rays(arena: &Arena, tracks: &[Track<'_>], rays: &[Ray<'_>], title: &str) -> String {
    render_with_stretches(arena, tracks, &[], rays, title)
}

/// [`render_with_rays`] with stretches drawn over the tracks, a legend row
/// per label (the legend is inside the picture, below the arena).
pub fn render_with_stretches(
    arena: &Arena,
    tracks: &[Track<'_>],
    stretches: &[Stretch<'_>],
    rays: &[Ray<'_>],
    title: &str,
) -> String {
    // a legend row per label, in order of first appearance
    let mut labels: std::vec::Vec<&Stretch<'_>> = std::vec::Vec::new();
    for st in stretches {
        if !labels.iter().any(|l| l.label == st.label) {
            labels.push(st);
        }
    }
    let rows = tracks.len() + labels.len() + 1 + usize::from(!rays.is_empty());
    let legend_h = LEGEND_ROW * rows as f64;
    // wide enough for the box and for every line of text (title, legend)
    let room = |x: f64, text: &str| x + CHAR_PX * text.chars().count() as f64 + MARGIN;
    let texts =
        tracks.iter().map(|t| room(LEGEND_TEXT_X, t.label)).chain(labels.iter().map(|l| room(LEGEND_TEXT_X, &l.label)));
    let fixed = [title, RAYS_LEGEND, ENDS_LEGEND, &arena_line(arena)].map(|t| room(MARGIN, t));
    let w = texts.chain(fixed).fold(arena.width_y_mm() + 2.0 * MARGIN, f64::max);
    let h = arena.length_x_mm() + 2.0 * MARGIN + legend_h;
    // (x north, y east) -> (svg x right, svg y down)
    let px = |p: &PoseF64| (MARGIN + p.y, MARGIN + arena.length_x_mm() - p.x);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{h:.0}" viewBox="0 0 {w:.1} {h:.1}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r##"<rect x="{MARGIN}" y="{MARGIN}" width="{:.1}" height="{:.1}" fill="#f4f1e8" stroke="black" stroke-width="2"/>"##,
        arena.width_y_mm(),
        arena.length_x_mm()
    );
    let _ = writeln!(s, r#"<text x="{MARGIN}" y="{:.1}">{}</text>"#, MARGIN - 22.0, escape(title));
    let _ = writeln!(s, r#"<text x="{MARGIN}" y="{:.1}">{}</text>"#, MARGIN - 6.0, arena_line(arena));
    for r in rays {
        let (x1, y1) = px(&PoseF64::new(r.from.0, r.from.1, 0.0));
        let (x2, y2) = px(&PoseF64::new(r.to.0, r.to.1, 0.0));
        let _ = writeln!(
            s,
            r#"<line x1="{x1:.1}" y1="{y1:.1}" x2="{x2:.1}" y2="{y2:.1}" stroke="{c}" stroke-width="0.5" stroke-opacity="0.5"/><circle cx="{x2:.1}" cy="{y2:.1}" r="2" fill="{c}"/>"#,
            c = r.color
        );
    }
    for t in tracks {
        if t.poses.is_empty() {
            continue;
        }
        polyline(&mut s, t.poses.iter().map(&px), t.color, 1.5, t.dashed.then_some("6 4"));
        for (p, fill) in [(t.poses.first(), "white"), (t.poses.last(), t.color)] {
            let Some(p) = p else { continue };
            let (x, y) = px(p);
            let (sn, cs) = p.theta.sin_cos();
            let (ax, ay) = px(&PoseF64::new(p.x + ARROW * cs, p.y + ARROW * sn, 0.0));
            let _ = writeln!(
                s,
                r#"<line x1="{x:.1}" y1="{y:.1}" x2="{ax:.1}" y2="{ay:.1}" stroke="{}" stroke-width="2"/><circle cx="{x:.1}" cy="{y:.1}" r="4" fill="{fill}" stroke="{}"/>"#,
                t.color, t.color
            );
        }
    }
    for st in stretches {
        polyline(&mut s, st.poses.iter().map(&px), st.color, 3.0, st.dashed.then_some("3 3"));
    }
    let mut ly = MARGIN + arena.length_x_mm() + MARGIN * 0.5 + LEGEND_ROW;
    let rows = tracks.iter().map(|t| (t.label, t.color, t.dashed, "2", "6 4"));
    for (label, color, dashed, width, pattern) in
        rows.chain(labels.iter().map(|l| (&*l.label, l.color, l.dashed, "3", "3 3")))
    {
        let dash = if dashed { std::format!(r#" stroke-dasharray="{pattern}""#) } else { String::new() };
        let _ = writeln!(
            s,
            r#"<line x1="{MARGIN}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{}" stroke-width="{width}"{dash}/><text x="{:.1}" y="{:.1}">{}</text>"#,
            ly - 4.0,
            MARGIN + 30.0,
            ly - 4.0,
            color,
            LEGEND_TEXT_X,
            ly,
            escape(label)
        );
        ly += LEGEND_ROW;
    }
    if !rays.is_empty() {
        let _ = writeln!(s, r#"<text x="{MARGIN}" y="{ly:.1}">{RAYS_LEGEND}</text>"#);
        ly += LEGEND_ROW;
    }
    let _ = writeln!(s, r#"<text x="{MARGIN}" y="{ly:.1}">{ENDS_LEGEND}</text></svg>"#);
    s
}

const RAYS_LEGEND: &str =
    "thin lines and dots: each lidar reading, from the lidar to where its beam ended (a colour per lidar)";
const ENDS_LEGEND: &str = "open circle: start; filled: end; line: heading";

fn arena_line(arena: &Arena) -> String {
    std::format!("N ^  arena {:.1} x {:.1} mm (x north, y east), 1 px = 1 mm", arena.length_x_mm(), arena.width_y_mm())
}

fn escape(t: &str) -> String {
    t.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// A `<polyline>` through `points` (svg coordinates), dashed when asked.
fn polyline(s: &mut String, points: impl Iterator<Item = (f64, f64)>, color: &str, width: f64, dash: Option<&str>) {
    let mut pts = String::new();
    for (x, y) in points {
        let _ = write!(pts, "{x:.1},{y:.1} ");
    }
    let _ = write!(s, r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="{width}""#, pts.trim_end());
    if let Some(d) = dash {
        let _ = write!(s, r#" stroke-dasharray="{d}""#);
    }
    let _ = writeln!(s, "/>");
}
