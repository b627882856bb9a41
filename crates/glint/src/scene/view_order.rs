//! Beginner layer: the order views are drawn in when some draw into render
//! targets that others show. One rule for `.scn` loading (which refuses a
//! cycle at a camera's line) and for the renderer (which draws in this order).

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The order to draw views in: every view that draws into a target before each
/// view that shows it, and otherwise the given order (the lowest ready view first).
///
/// - `outputs[k]`: the target view k draws into (`None`: the image);
/// - `shown[k]`: the targets view k shows, each once (its own left out: a view
///   never shows its own target);
/// - targets are numbered below `targets`.
///
/// Linear in views plus the targets they show (Kahn's sort, with each target a
/// node between the views drawing it and the views showing it). Returns the
/// first view that cannot be drawn when views need each other's targets in a
/// circle.
pub fn draw_order(outputs: &[Option<usize>], shown: &[Vec<usize>], targets: usize) -> Result<Vec<usize>, usize> {
    let mut writers = vec![0usize; targets];
    for t in outputs.iter().flatten() {
        writers[*t] += 1;
    }
    let mut readers: Vec<Vec<usize>> = vec![Vec::new(); targets];
    let mut waits = vec![0usize; outputs.len()];
    for (view, shows) in shown.iter().enumerate() {
        for &t in shows.iter().filter(|&&t| writers[t] > 0) {
            readers[t].push(view);
            waits[view] += 1;
        }
    }
    let mut ready: BinaryHeap<Reverse<usize>> = (0..outputs.len()).filter(|&v| waits[v] == 0).map(Reverse).collect();
    let mut order = Vec::with_capacity(outputs.len());
    while let Some(Reverse(view)) = ready.pop() {
        order.push(view);
        let Some(t) = outputs[view] else { continue };
        writers[t] -= 1;
        if writers[t] == 0 {
            for &reader in &readers[t] {
                waits[reader] -= 1;
                if waits[reader] == 0 {
                    ready.push(Reverse(reader));
                }
            }
        }
    }
    match (0..outputs.len()).find(|&v| waits[v] > 0 && outputs[v].is_some()) {
        Some(stuck) if order.len() < outputs.len() => Err(stuck),
        _ if order.len() < outputs.len() => Err((0..outputs.len()).find(|&v| waits[v] > 0).unwrap_or(0)),
        _ => Ok(order),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_drawing_targets_come_before_the_views_showing_them() {
        // View 0 shows target 1, which view 2 draws; view 1 draws target 0, shown by view 2.
        let outputs = [None, Some(0), Some(1)];
        let shown = [vec![1], vec![], vec![0]];
        assert_eq!(draw_order(&outputs, &shown, 2), Ok(vec![1, 2, 0]));
        // Nothing to wait for: the given order.
        assert_eq!(draw_order(&[None, None, Some(0)], &[vec![], vec![], vec![]], 1), Ok(vec![0, 1, 2]));
        // A target nobody draws is no reason to wait.
        assert_eq!(draw_order(&[None], &[vec![0]], 1), Ok(vec![0]));
    }

    #[test]
    fn a_target_waits_for_every_view_drawing_it() {
        let outputs = [None, Some(0), Some(0)];
        let shown = [vec![0], vec![], vec![]];
        assert_eq!(draw_order(&outputs, &shown, 1), Ok(vec![1, 2, 0]));
    }

    #[test]
    fn a_cycle_names_a_view_in_it() {
        let outputs = [None, Some(0), Some(1)];
        let shown = [vec![0], vec![1], vec![0]];
        assert_eq!(draw_order(&outputs, &shown, 2), Err(1));
    }

    #[test]
    fn ten_thousand_views_order_quickly() {
        // A chain: view k draws target k and shows target k + 1, so the order is reversed.
        let n = 10_000;
        let outputs: Vec<Option<usize>> = (0..n).map(Some).collect();
        let shown: Vec<Vec<usize>> = (0..n).map(|k| if k + 1 < n { vec![k + 1] } else { vec![] }).collect();
        let order = draw_order(&outputs, &shown, n).unwrap();
        assert_eq!(order, (0..n).rev().collect::<Vec<_>>());
    }
}
