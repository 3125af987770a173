//! Greedy vertex colouring: no two vertices of a colour are neighbours, so a colour's vertices can
//! be updated in any order, or in parallel, with the same result.

/// Colours the vertices of a graph given by each vertex's neighbours: returns the vertices in
/// colour order and each colour's range. Deterministic: vertices are taken in index order.
pub fn vertices(neighbours: &[Vec<u32>]) -> (Vec<u32>, Vec<std::ops::Range<usize>>) {
    let n = neighbours.len();
    let mut colour = vec![u32::MAX; n];
    let mut taken: Vec<bool> = Vec::new();
    let mut count = 0u32;
    for v in 0..n {
        taken.clear();
        taken.resize(count as usize + 1, false);
        for &w in &neighbours[v] {
            let c = colour[w as usize];
            if (c as usize) < taken.len() {
                taken[c as usize] = true;
            }
        }
        let c = taken.iter().position(|t| !t).unwrap_or(taken.len()) as u32;
        colour[v] = c;
        count = count.max(c + 1);
    }
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by_key(|&v| (colour[v as usize], v));
    let mut ranges = Vec::with_capacity(count as usize);
    let mut start = 0;
    for c in 0..count {
        let len = colour.iter().filter(|&&x| x == c).count();
        ranges.push(start..start + len);
        start += len;
    }
    (order, ranges)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_two_neighbours_share_a_colour() {
        // A 5 x 5 grid with diagonals (as cloth springs connect it).
        let id = |x: i32, y: i32| (y * 5 + x) as u32;
        let mut nb = vec![Vec::new(); 25];
        for y in 0..5 {
            for x in 0..5 {
                for (dx, dy) in [(1, 0), (0, 1), (1, 1), (-1, 1), (2, 0), (0, 2)] {
                    let (u, v) = (x + dx, y + dy);
                    if (0..5).contains(&u) && (0..5).contains(&v) {
                        nb[id(x, y) as usize].push(id(u, v));
                        nb[id(u, v) as usize].push(id(x, y));
                    }
                }
            }
        }
        let (order, ranges) = vertices(&nb);
        assert_eq!(order.len(), 25);
        let mut colour = [0; 25];
        for (c, r) in ranges.iter().enumerate() {
            for &v in &order[r.clone()] {
                colour[v as usize] = c;
            }
        }
        for v in 0..25 {
            for &w in &nb[v] {
                assert_ne!(colour[v], colour[w as usize], "{v} and {w}");
            }
        }
        assert!(ranges.len() <= 12, "{} colours", ranges.len());
    }
}
