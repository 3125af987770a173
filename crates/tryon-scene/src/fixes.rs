//! The keys that exist to fix one symptom (of a garment, a clip or a body), grouped in one list
//! so a reader sees what each is for and which decision made it. The reference
//! (docs/scenes.md) prints them as one table; the tests check that every key is in the schema
//! and every decision is a live topic of docs/decisions.

/// A key that fixes one symptom.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fix {
    /// The key as `--set` spells it (`effects.body_press`); for a kind's key, the table, the
    /// kind in parentheses and the key (`motion(bvh).arm_clearance`).
    pub key: &'static str,
    /// The symptom it fixes.
    pub symptom: &'static str,
    /// The topic of the decision that made it, in docs/decisions/README.md.
    pub decision: &'static str,
}

/// Every symptom fix, by where it acts: the motion, the body, the garment, the cloth, the surface.
pub const FIXES: &[Fix] = &[
    Fix {
        key: "motion(bvh).arm_clearance",
        symptom: "a clip's arms swing through the hips of a wider body, or a hand into the face",
        decision: "retargeting",
    },
    Fix {
        key: "motion(bvh).max_turn",
        symptom: "a capture glitch spins a joint (131_01's right wrist) and flings the sleeve",
        decision: "retargeting",
    },
    Fix {
        key: "scene.body_step",
        symptom: "a fast limb passes through the cloth between two collider updates",
        decision: "body step",
    },
    Fix {
        key: "effects.body_press",
        symptom: "skinning passes an arm into the chest or a thigh into the other; cloth is caught inside",
        decision: "body press",
    },
    Fix {
        key: "garment(mhclo).closures",
        symptom: "a buttoned front or a shut slit, modelled as touching borders, falls open",
        decision: "garment fit",
    },
    Fix {
        key: "garment(mhclo).band_gap",
        symptom: "a garment slides down the body (waistbands, collars, cuffs grip it)",
        decision: "garment fit",
    },
    Fix {
        key: "garment(mhclo).waist_gap",
        symptom: "a waist looser than the band gap slides down (held as a belt holds it)",
        decision: "waist belt",
    },
    Fix {
        key: "cloth.p1.stretch_guard",
        symptom: "a P1 substep overstretches an edge at a strap or seam",
        decision: "stretch guard",
    },
    Fix {
        key: "cloth.vbd.swept",
        symptom: "a particle tunnels through the body within one step",
        decision: "swept collision",
    },
    Fix {
        key: "cloth.vbd.limit",
        symptom: "a free-hanging sheet stretches under VBD (off for garments on a body)",
        decision: "vbd strain limit",
    },
    Fix {
        key: "effects.fine_pokes",
        symptom: "a nipple, knuckle or horn pokes through the refined surface between its vertices",
        decision: "fine pokes",
    },
    Fix {
        key: "effects.max_fine_stretch",
        symptom: "wrinkle heights stretch a fine edge far past its length",
        decision: "wrinkle model",
    },
    Fix {
        key: "effects.wrinkle_min_compression",
        symptom: "a slightly compressed coarse garment is ribbed all over like a knit",
        decision: "wrinkle model",
    },
];

/// The fixes as a Markdown section of the reference.
pub fn markdown() -> String {
    let mut s = String::from(
        "\n## Fixes for particular symptoms\n\n\
         These keys exist to fix one symptom each; their defaults are what the project runs. Each\n\
         names the decision that made it (docs/decisions/README.md, by topic).\n\n\
         | key | the symptom it fixes | decision |\n|---|---|---|\n",
    );
    for f in FIXES {
        s.push_str(&format!(
            "| `{}` | {} | *{}* |\n",
            f.key, f.symptom, f.decision
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// (table, kind, name) of a fix's key.
    fn parts(key: &str) -> (String, Option<String>, String) {
        let (path, name) = key.rsplit_once('.').expect("a key has a table");
        match path.split_once('(') {
            Some((table, kind)) => (
                table.to_string(),
                Some(kind.trim_end_matches(')').to_string()),
                name.to_string(),
            ),
            None => (path.to_string(), None, name.to_string()),
        }
    }

    #[test]
    fn every_fix_is_a_key_of_the_schema() {
        let keys = crate::docs::keys();
        for f in FIXES {
            let (table, kind, name) = parts(f.key);
            let found = keys
                .iter()
                .any(|k| k.table == table && k.name == name && (kind.is_none() || k.kind == kind));
            assert!(found, "{}: not a key of the schema", f.key);
        }
    }

    #[test]
    fn every_fix_names_a_live_decision() {
        let index = include_str!("../../../docs/decisions/README.md");
        let live = &index[..index.find("## Tried and dropped").unwrap_or(index.len())];
        for f in FIXES {
            assert!(
                live.contains(&format!("| {} |", f.decision)),
                "{}: decision *{}* is not a live topic",
                f.key,
                f.decision
            );
        }
    }

    #[test]
    fn a_key_that_is_not_in_the_schema_is_found_missing() {
        // The check above can fail: a made-up key is not found.
        let keys = crate::docs::keys();
        let (table, kind, name) = parts("motion(bvh).no_such_key");
        assert_eq!(kind.as_deref(), Some("bvh"));
        assert!(!keys.iter().any(|k| k.table == table && k.name == name));
    }
}
