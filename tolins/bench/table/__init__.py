"""What the bench measures and how it is summarised: Table 1's rows and trainings
(:mod:`.rows`), the evaluation seeds (:mod:`.seeds`), the robustness table
(:mod:`.robustness`), a row's figures and ``results.json`` (:mod:`.results`), interval
estimates (:mod:`.statistics`), the paper's claims (:mod:`.claims`), two results side by
side (:mod:`.compare`), the contact-force columns (:mod:`.force_table`) and the env-step
curves of RS-GAIL and the deep-RL baselines (:mod:`.baselines`). Nothing here runs an
episode or writes a stage."""
