"""The timed motion of a job.

* :mod:`.assemble` — approach, passes, transits and retract, timed and labelled;
* :mod:`.transit` — joint moves between passes clear of the stock;
* :mod:`.densify` — rulings added where the timed wire leaves the surface;
* :mod:`.corners` — where the wire stops; :mod:`.feed_limit` — what holds the feed;
* :mod:`.timing` — the time law (toppra and a closed-form reachability pass).
"""
