"""Jobs: what the commands run, one layer above the library.

The domain packages (earth, rotations, strapdown, simulation, alignment,
filters, integration, analysis, io) never import from here.  Each job reads
its configuration, calls the library, scores, writes files and plots; the CLI
(:mod:`inskit.cli`) only parses arguments, calls one job and prints.

* :mod:`.navigate` and :mod:`.config`: the main job (IMU + GNSS -> solution)
  and its validated TOML configuration;
* :mod:`.outages`: outage protocols and their scoring;
* :mod:`.plots`: the run plots;
* :mod:`.montecarlo`: consistency studies (``run_once`` / ``reduce_runs`` /
  a pluggable ``map``) and the scheme comparison;
* :mod:`.simulate`: files and plots of a simulated scenario;
* :mod:`.allan`: Allan deviation to a ``[noise]`` section;
* :mod:`.reproduce_alignment`: source 002's experiments;
* :mod:`.bench`, :mod:`.demo`: throughput and closed-form demonstrations.
"""
