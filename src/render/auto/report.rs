//! What `--strategy auto` tells: the pilots' table for the terminal and `--stats`, and the line
//! of the EXR's metadata.

use super::*;

impl Choice {
    /// The pilots as a table, and the choice, for the terminal.
    pub fn table(&self) -> String {
        let unit = match self.cost {
            Cost::Rays => "Mrays",
            Cost::Seconds => "seconds",
        };
        let scale = match self.cost {
            Cost::Rays => 1e-6,
            Cost::Seconds => 1.0,
        };
        let w = (self.rows.iter())
            .map(|r| r.candidate.to_string().len())
            .max()
            .unwrap_or(8)
            .max(8);
        let first = self.first.to_string();
        let probe = format!(
            "{:.0}% of {first}'s light indirect in a probe of {} spp",
            100.0 * self.indirect,
            self.probe
        );
        if self.rows.is_empty() {
            let s = format!(
                "auto: {} chosen without a pilot (a probe of {} spp on {} of {} tiles in {:.2} s: \
                 {:.0}% of {first}'s light indirect)\n",
                self.candidate,
                self.probe,
                self.tiles.0,
                self.tiles.1,
                self.elapsed.as_secs_f64(),
                100.0 * self.indirect,
            );
            return s + &self.stage_lines(&first, &self.caustic_words(&first));
        }
        let spp = self.rows.first().map_or(0, |r| r.spp);
        let early = match spp < self.planned {
            true => format!(
                ", early: decided beyond doubt before the {} planned",
                self.planned
            ),
            false => String::new(),
        };
        let mut s = format!(
            "auto: pilots of {spp} spp ({} replicates{early}) on {} of {} tiles in {:.2} s ({probe})\n  {:w$}  {:>10}  {:>9}  {:>9}  {:>10}\n",
            PILOT_REPLICATES,
            self.tiles.0,
            self.tiles.1,
            self.elapsed.as_secs_f64(),
            "strategy",
            "relMSE",
            "± se",
            unit,
            "efficiency",
        );
        let e0 = self.rows.first().map_or(f64::NAN, |r| r.efficiency);
        for (k, r) in self.rows.iter().enumerate() {
            let mark = match (k == self.index, self.stage) {
                (false, _) => "",
                (true, GuidedStage::Rendered) => " <- chosen, with guided directions",
                (true, _) => " <- chosen",
            };
            s += &format!(
                "  {:w$}  {:>10.3e}  {:>9.1e}  {:>9.3}  {:>10.2}{mark}\n",
                r.candidate.to_string(),
                r.rel_mse,
                r.rel_mse_se,
                r.cost * scale,
                r.efficiency / e0,
            );
        }
        s += &self.stage_lines(&first, &self.caustic_words(&first));
        s + &format!(
            "  efficiency relative to {first}; the best against it: z = {:.1} (switch above {SWITCH_Z}){}\n",
            self.z,
            self.weights()
        )
    }

    /// The first candidate's (`first`'s) caustic share against the gate, as the table words it.
    fn caustic_words(&self, first: &str) -> String {
        format!(
            "{:.0}% of {first}'s light caustic, gate {:.0}%",
            100.0 * self.caustic,
            100.0 * CAUSTIC_GATE
        )
    }

    /// The table's lines on what became of the guided candidates and on the candidates not
    /// piloted, and why (`first`: the first candidate's name; `caustic`: its light's caustic
    /// share against the gate, as the table words it).
    fn stage_lines(&self, first: &str, caustic: &str) -> String {
        let mut s = String::new();
        // the row chosen (with `Rendered`, the twin's unguided candidate), the first without one
        let chosen = self
            .rows
            .get(self.index)
            .map_or(self.first, |r| r.candidate);
        let unpiloted = match self.stage {
            GuidedStage::Shut => format!("guided, no unguided candidate beat {first}, {caustic}"),
            GuidedStage::Piloted => format!("guided, not the guided twin of {chosen}"),
            GuidedStage::Rendered => format!("{chosen}'s guided twin renders instead"),
            GuidedStage::Unread => format!(
                "the guided twin of {chosen}: its training would end before its gate's first \
                 reading"
            ),
        };
        if self.stage == GuidedStage::Rendered {
            s += &format!(
                "  {}: rendered without a pilot ({caustic}): its guide trained over the image, \
                 its gate against Phong directions\n",
                self.candidate
            );
        } else if self.stage == GuidedStage::Piloted && self.caustic >= CAUSTIC_GATE {
            s += &format!("  guided candidates piloted: {caustic}\n");
        }
        let (unshared, others) = self.unpiloted_by_reason();
        if !unshared.is_empty() {
            s += &format!(
                "  {unshared}: not piloted ({:.0}% of {first}'s light indirect, gate {:.0}%: path \
                 reuse shares only that)\n",
                100.0 * self.indirect,
                100.0 * INDIRECT_GATE
            );
        }
        if !others.is_empty() {
            s += &format!("  {others}: not piloted ({unpiloted})\n");
        }
        s
    }

    /// The candidates not piloted, comma-separated.
    fn unpiloted_names(&self) -> String {
        (self.unpiloted.iter())
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The candidates not piloted, comma-separated, in two lists: those with path reuse where
    /// too little of the light was indirect ([`INDIRECT_GATE`]), and the others (guided ones
    /// the stage left out: [`GuidedStage`]).
    fn unpiloted_by_reason(&self) -> (String, String) {
        let direct = self.indirect < INDIRECT_GATE;
        let (unshared, others): (Vec<_>, Vec<_>) = (self.unpiloted.iter())
            .map(|c| (c.reuse > 1 && direct, c.to_string()))
            .partition(|(u, _)| *u);
        let names =
            |v: Vec<(bool, String)>| v.into_iter().map(|(_, n)| n).collect::<Vec<_>>().join(", ");
        (names(unshared), names(others))
    }

    /// What the table's rays weigh, when they are not all one: a reuse connection's shadow ray,
    /// an EARS candidate's ray, a guided candidate's ray.
    fn weights(&self) -> String {
        let mut s = String::new();
        if self.cost == Cost::Rays {
            if self.rows.iter().any(|r| r.candidate.reuse > 1) {
                s += &format!("; a reuse connection's ray counts {CONNECTION_COST}");
            }
            if (self.rows.iter()).any(|r| r.candidate.roulette == Roulette::Ears) {
                s += &format!("; an EARS ray counts {EARS_RAY_COST}");
            }
            if (self.rows.iter()).any(|r| r.candidate.strategy.directions == Directions::Guided) {
                s += &format!("; a guided ray counts {GUIDED_RAY_COST}");
            }
        }
        s
    }

    /// One line for the metadata: the choice, each candidate's relative efficiency, z, the
    /// pilots' spp and cost.
    pub fn record(&self) -> String {
        let e0 = self.rows.first().map_or(f64::NAN, |r| r.efficiency);
        let rows: Vec<String> = (self.rows.iter())
            .map(|r| format!("{} {:.3}", r.candidate, r.efficiency / e0))
            .collect();
        let rows = match rows.is_empty() {
            true => "no pilot".to_string(),
            false => format!("efficiency {}", rows.join(", ")),
        };
        let unpiloted = match self.unpiloted.is_empty() {
            true => String::new(),
            false => format!(" (not piloted: {})", self.unpiloted_names()),
        };
        let rendered = match self.stage {
            GuidedStage::Rendered => " (rendered without a pilot, gated)",
            _ => "",
        };
        format!(
            "chose {}{rendered}; {rows}{unpiloted}; z {:.2}; caustic {:.3}; indirect {:.3}; probe {} spp; pilots {} spp of {} planned on {} of {} tiles, cost {}",
            self.candidate,
            self.z,
            self.caustic,
            self.indirect,
            self.probe,
            self.rows.first().map_or(0, |r| r.spp),
            self.planned,
            self.tiles.0,
            self.tiles.1,
            match self.cost {
                Cost::Rays => "rays",
                Cost::Seconds => "seconds",
            }
        )
    }
}
