"""The bearing-identify command line (identify_cli.main)."""

import json

import pytest

from bearing_observer.identify_cli import main
from bearing_observer.model_sets import load_model_set


def test_bad_arguments(tmp_path, capsys):
    assert main(["--source", "x.mat", "--sample-rate", "12000", "--model-set", "t",
                 "--out", str(tmp_path)]) == 2
    assert "needs --fault" in capsys.readouterr().err
    assert main(["--source", "x.mat", "--fault", "outer_race", "--sample-rate", "12000",
                 "--model-set", "t", "--out", str(tmp_path)]) == 1
    assert "no such file" in capsys.readouterr().err
    assert main(["--source", "sim", "--model-set", "t", "--out", str(tmp_path)]) == 1
    assert "--source sim needs --sample-rate" in capsys.readouterr().err
    assert main(["--source", "sim", "--sample-rate", "12000", "--model-set", "none"]) == 2
    assert "invalid model set name 'none'" in capsys.readouterr().err
    assert main(["--source", "sim", "--sample-rate", "12000", "--model-set", "t", "--bearing", "nope"]) == 2
    assert "unknown bearing 'nope'" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["--sample-rate", "12000", "--model-set", "t"])  # --source missing


def test_identifies_cwru_set_with_provenance(tmp_path, capsys, cwru_record):
    outer, inner = cwru_record("130_OR007at6_0hp_DE12k.mat"), cwru_record("105_IR007_0hp_DE12k.mat")
    rc = main(["--source", f"outer_race={outer}",
               "--source", f"inner_race={inner}",
               "--sample-rate", "12000", "--orders", "6", "6", "0", "--max-seconds", "1.0",
               "--model-set", "tiny", "--out", str(tmp_path)])
    assert rc == 0
    lines = [json.loads(x) for x in capsys.readouterr().out.splitlines()]
    assert [x["fault"] for x in lines] == ["outer_race", "inner_race"]
    models = load_model_set("tiny", sample_rate=12000.0, root=tmp_path)
    prov = models["outer_race"].provenance
    assert prov["file"] == "130_OR007at6_0hp_DE12k.mat" and len(prov["sha256"]) == 64
    assert prov["command"].startswith("bearing-identify --source outer_race=")
    assert models["outer_race"].nb == 6
