//! Consistent winding: triangles flipped, one connected piece at a time, so every shared edge is
//! walked in opposite directions by its two triangles.

use std::collections::HashMap;

/// Flips triangles of `tris` (over `n` vertices) until neighbours agree; the first triangle of
/// each connected piece keeps its winding. Returns which were flipped.
pub fn orient(tris: &mut [[u32; 3]], n: usize) -> Vec<bool> {
    let _ = n;
    let mut by_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (t, tri) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            by_edge.entry((a.min(b), a.max(b))).or_default().push(t);
        }
    }
    let mut flipped = vec![false; tris.len()];
    let mut done = vec![false; tris.len()];
    let mut stack = Vec::new();
    for start in 0..tris.len() {
        if done[start] {
            continue;
        }
        done[start] = true;
        stack.push(start);
        while let Some(t) = stack.pop() {
            let tri = tris[t];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                for &u in &by_edge[&(a.min(b), a.max(b))] {
                    if done[u] {
                        continue;
                    }
                    // The neighbour must walk the edge b -> a.
                    let o = tris[u];
                    let same = (0..3).any(|m| o[m] == a && o[(m + 1) % 3] == b);
                    if same {
                        tris[u].swap(1, 2);
                        flipped[u] = !flipped[u];
                    }
                    done[u] = true;
                    stack.push(u);
                }
            }
        }
    }
    flipped
}
