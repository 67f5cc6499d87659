"""report.html on a narrow page: tables wrap (also after underscores) or scroll in their own box."""

from mpcshare.reports.html import markdown_to_html


def test_tables_can_wrap_and_scroll_and_the_page_fits_a_phone(tmp_path):
    md = "| run | tracking RMS [mm] |\n|---|---|\n| random_handover | 16.9 |\n\n[a_link](http://x.org/a_b)\n"
    page, missing = markdown_to_html(md, tmp_path)
    assert missing == []
    assert '<meta name="viewport" content="width=device-width' in page
    assert '<div class="table"><table>' in page and "</table></div>" in page
    assert "random_<wbr>handover" in page
    assert 'href="http://x.org/a_b"' in page and ">a_link<" in page  # outside tables nothing changes
