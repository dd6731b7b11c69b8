//! Where the survey's turns have taken the body, in steps of
//! [`crate::config::locate::TURN_DEG`] from the first view, clockwise positive:
//! the ground swept between its two edges, the view taken at each edge,
//! and which ways were blocked. Each pair is indexed counterclockwise (0)
//! and clockwise (1).

#[derive(Clone, Copy, Debug)]
pub struct Sweep {
    at: i8,
    /// The farthest turned each way: the ground between was swept, and a
    /// view taken at every turn.
    edges: [i8; 2],
    /// The view (its index) taken at each edge.
    edge_views: [usize; 2],
    /// A turn that way was blocked (the compass showed it).
    blocked: [bool; 2],
    /// Steps of the turn under way: from where it is past the edge that
    /// way (back over swept ground, then one step onto new).
    steps: u8,
}

impl Sweep {
    /// At the first view, nothing swept.
    pub const START: Sweep = Sweep { at: 0, edges: [0, 0], edge_views: [0, 0], blocked: [false, false], steps: 1 };

    /// The turn under way that way was blocked: the body stayed.
    pub fn blocked(&mut self, clockwise: bool) {
        if let Some(b) = self.blocked.get_mut(usize::from(clockwise)) {
            *b = true;
        }
    }

    /// The turn under way that way went its steps.
    pub fn turned(&mut self, clockwise: bool) {
        let step = if clockwise { self.steps as i8 } else { (self.steps as i8).saturating_neg() };
        self.at = self.at.saturating_add(step);
        let [ccw, cw] = &mut self.edges;
        (*ccw, *cw) = ((*ccw).min(self.at), (*cw).max(self.at));
    }

    /// View `index` is taken where the body is: an edge's view when it is
    /// at one.
    pub fn view_taken(&mut self, index: usize) {
        for (edge, view) in self.edges.iter().zip(self.edge_views.iter_mut()) {
            if *edge == self.at {
                *view = index;
            }
        }
    }

    /// The view taken at the edge that way, unless a turn that way was
    /// blocked.
    pub fn open_edge_view(&self, clockwise: bool) -> Option<usize> {
        let way = usize::from(clockwise);
        if self.blocked.get(way) == Some(&false) {
            self.edge_views.get(way).copied()
        } else {
            None
        }
    }

    /// The next turn goes that way, back over the swept ground and one
    /// step past its edge: its steps.
    pub fn plan(&mut self, clockwise: bool) -> u8 {
        let [ccw, cw] = self.edges;
        let steps = if clockwise { cw.saturating_sub(self.at) } else { self.at.saturating_sub(ccw) };
        self.steps = steps.saturating_add(1).unsigned_abs();
        self.steps
    }
}
