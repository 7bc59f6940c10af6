"""A ``tolins bench`` run: what it runs (:mod:`.config`, the budgets in :mod:`.profiles`),
each stage's settings from those budgets (:mod:`.settings`), the stages planned once
(:mod:`.plan`), the run itself (:mod:`.runner`) and where its jobs run (:mod:`.executor`),
the folder's lock (:mod:`.lock`), its progress bar (:mod:`.progress`) and its timeline
(:mod:`.timeline`)."""
